/* imm-monoslam — the online keyframe smoother (see CKeyframeSmoother.h). */
#include <immslam/eval/statistics.h>
#include <immslam/math/quaternion.h>
#include <immslam/refine/CKeyframeSmoother.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>
#include <limits>
#include <map>
#include <stdexcept>
#include <unordered_map>

namespace immslam::refine
{
namespace
{
constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();

/** CPU time of the calling thread (seconds). */
double threadCpuSeconds()
{
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

/** a * b of poses T_W_C (b expressed in a's camera frame). */
core::TStampedPose compose(const core::TStampedPose& a, const core::TStampedPose& b)
{
  core::TStampedPose c = b;
  c.p_W_C = a.p_W_C + math::quatRotate(a.q_W_C, b.p_W_C);
  c.q_W_C = math::quatNormalized(math::quatMultiply(a.q_W_C, b.q_W_C));
  return c;
}

/** a^-1 * b: the pose b in the camera frame of a. */
core::TStampedPose between(const core::TStampedPose& a, const core::TStampedPose& b)
{
  core::TStampedPose c = b;
  const Vec4 qa_inv = math::quatConjugate(a.q_W_C);
  c.p_W_C = math::quatRotate(qa_inv, b.p_W_C - a.p_W_C);
  c.q_W_C = math::quatNormalized(math::quatMultiply(qa_inv, b.q_W_C));
  return c;
}

/** `rel` (a pose in the frame of `from`) moved onto `to`, keeping rel's timestamp. */
core::TStampedPose carried(const core::TStampedPose& to, const core::TStampedPose& from, const core::TStampedPose& p)
{
  core::TStampedPose out = compose(to, between(from, p));
  out.timestamp = p.timestamp;
  return out;
}
}  // namespace

CKeyframeSmoother::CKeyframeSmoother(const TOptions& opts, double fx, double fy) : m_opts(opts), m_fx(fx), m_fy(fy)
{
  if (m_opts.windowKeyframes < m_opts.heldKeyframes + 1)
    throw std::invalid_argument("CKeyframeSmoother: windowKeyframes must exceed heldKeyframes");
  if (m_opts.minViews < 2) throw std::invalid_argument("CKeyframeSmoother: minViews must be >= 2");
  if (!m_opts.synchronous) m_thread = std::thread([this] { run(); });
}

CKeyframeSmoother::~CKeyframeSmoother()
{
  try
  {
    finish();
  }
  catch (...)
  {
  }
}

void CKeyframeSmoother::addFrame(TSmootherFrame frame)
{
  if (m_opts.synchronous)
  {
    if (m_finished) throw std::logic_error("CKeyframeSmoother::addFrame after finish()");
    const double c0 = threadCpuSeconds();
    {
      std::lock_guard<std::mutex> lk(m_mutex);
      ++m_given;
    }
    if (ingest(std::move(frame))) optimiseWindow();
    std::lock_guard<std::mutex> lk(m_mutex);
    m_stats.cpuSeconds += threadCpuSeconds() - c0;
    return;
  }
  {
    std::lock_guard<std::mutex> lk(m_mutex);
    if (m_stop) throw std::logic_error("CKeyframeSmoother::addFrame after finish()");
    m_queue.push_back(std::move(frame));
    ++m_given;
  }
  m_wake.notify_one();
}

void CKeyframeSmoother::run()
{
  // The worker yields the CPU to the filter's thread when they compete (Linux: a per-thread nice).
  if (m_opts.workerNice > 0) setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), m_opts.workerNice);
  const double c0 = threadCpuSeconds();
  bool pending = false;  // a keyframe arrived whose optimisation was skipped
  for (;;)
  {
    TSmootherFrame frame;
    std::size_t backlog = 0;
    {
      std::unique_lock<std::mutex> lk(m_mutex);
      m_wake.wait(lk, [&] { return m_stop || !m_queue.empty(); });
      if (m_queue.empty()) break;  // stopped, and every frame handed over is done
      frame = std::move(m_queue.front());
      m_queue.pop_front();
      backlog = m_queue.size();
    }
    // Frames are taken one by one and the window optimised at every keyframe, as in a synchronous
    // run (same result), unless the worker is behind by more than maxBacklogFrames: then the
    // optimisation is left to a later keyframe (the lag stays bounded, the filter never waits).
    pending = ingest(std::move(frame)) || pending;
    if (pending && backlog <= m_opts.maxBacklogFrames)
    {
      optimiseWindow();
      pending = false;
    }
    std::lock_guard<std::mutex> lk(m_mutex);
    m_stats.cpuSeconds = threadCpuSeconds() - c0;
  }
  if (pending) optimiseWindow();
  std::lock_guard<std::mutex> lk(m_mutex);
  m_stats.cpuSeconds = threadCpuSeconds() - c0;
}

void CKeyframeSmoother::finish()
{
  if (m_opts.synchronous)
  {
    m_finished = true;
    return;
  }
  {
    std::lock_guard<std::mutex> lk(m_mutex);
    m_stop = true;
  }
  m_wake.notify_one();
  if (m_thread.joinable()) m_thread.join();
}

std::vector<double> CKeyframeSmoother::parallaxPx(const TKeyframe& kf, const TSmootherFrame& frame) const
{
  // Chain rule of the bearings: b_C = R_C_W R_W_K b_K for a point at infinity (no parallax).
  const Mat3 R_C_K = math::quatToRotation(frame.pose.q_W_C).transpose() * math::quatToRotation(kf.pub.filterPose.q_W_C);
  std::unordered_map<std::int64_t, Vec2> atKeyframe;
  for (const auto& m : kf.matches) atKeyframe.emplace(m.featureId, m.xn);
  std::vector<double> out;
  for (const auto& m : frame.matches)
  {
    const auto it = atKeyframe.find(m.featureId);
    if (it == atKeyframe.end()) continue;
    const Vec3 b = R_C_K * Vec3(it->second.x(), it->second.y(), 1);
    if (!(b.z() > 0)) continue;
    out.push_back(std::hypot(m_fx * (m.xn.x() - b.x() / b.z()), m_fy * (m.xn.y() - b.y() / b.z())));
  }
  return out;
}

bool CKeyframeSmoother::ingest(TSmootherFrame&& frame)
{
  // Only this thread (the worker, or the synchronous caller) changes the frames and keyframes; it
  // reads them without the lock and writes them under it.
  const std::size_t index = m_framePoses.size();
  bool isKeyframe = false;
  if (frame.matches.size() >= m_opts.minMatches)
  {
    if (m_keyframes.empty())
      isKeyframe = true;
    else
    {
      const TKeyframe& last = m_keyframes.back();
      const std::vector<double> parallax = parallaxPx(last, frame);
      const std::size_t shared = parallax.size();
      const bool due = static_cast<double>(shared) < m_opts.minOverlap * static_cast<double>(frame.matches.size()) ||
                       index - last.pub.frame >= m_opts.maxFrameGap;
      isKeyframe = due && (shared < m_opts.minMatches || eval::median(parallax) >= m_opts.minParallaxPx);
    }
  }
  std::lock_guard<std::mutex> lk(m_mutex);
  m_framePoses.push_back(frame.pose);
  ++m_stats.frames;
  if (!isKeyframe)
  {
    m_frameKeyframe.push_back(m_keyframes.empty() ? kNone : m_keyframes.size() - 1);
    return false;
  }
  TKeyframe kf;
  kf.pub.frame = index;
  kf.pub.filterPose = frame.pose;
  // Starts where the last keyframe's smoothed pose and the filter's motion since it put it.
  kf.pub.smoothedPose = m_keyframes.empty() ? frame.pose
                                            : carried(m_keyframes.back().pub.smoothedPose,
                                                      m_keyframes.back().pub.filterPose, frame.pose);
  kf.matches = std::move(frame.matches);
  m_frameKeyframe.push_back(m_keyframes.size());
  m_keyframes.push_back(std::move(kf));
  ++m_stats.keyframes;
  return true;
}

void CKeyframeSmoother::optimiseWindow()
{
  const std::size_t n = std::min(m_keyframes.size(), m_opts.windowKeyframes);
  if (n <= m_opts.heldKeyframes) return;  // nothing free yet
  const std::size_t first = m_keyframes.size() - n;
  // Held: the oldest heldKeyframes of the window. Until the window has slid past them, those are
  // the filter's first keyframes as they came: the smoothed trajectory takes the filter's frame and
  // scale over their span, and keeps it (a pair of early, close keyframes would set a poor scale).
  const std::size_t held = m_opts.heldKeyframes;

  // The window's problem: its keyframes' smoothed poses, the features measured by minViews of them.
  TBundleProblem p;
  p.fx = m_fx;
  p.fy = m_fy;
  std::map<std::int64_t, std::vector<TBundleObservation>> byFeature;
  for (std::size_t k = 0; k < n; ++k)
  {
    const TKeyframe& kf = m_keyframes[first + k];
    p.poses.push_back(kf.pub.smoothedPose);
    for (const auto& m : kf.matches) byFeature[m.featureId].push_back({k, 0, m.xn});
  }
  for (auto& [id, obs] : byFeature)
  {
    if (static_cast<int>(obs.size()) < m_opts.minViews) continue;
    for (auto& o : obs) o.point = p.featureIds.size();
    p.featureIds.push_back(id);
    p.obs.insert(p.obs.end(), obs.begin(), obs.end());
  }
  if (p.featureIds.empty()) return;
  p.points.assign(p.featureIds.size(), Vec3::Zero());
  triangulateAll(p);

  TBundleOptions bo;
  bo.huberPx = m_opts.huberPx;
  bo.maxIterations = m_opts.maxIterations;
  for (std::size_t k = 0; k < held; ++k) bo.heldPoses.push_back(k);
  bundleAdjust(p, bo);

  std::lock_guard<std::mutex> lk(m_mutex);
  ++m_stats.optimisations;
  for (std::size_t k = held; k < n; ++k)
  {
    TSmoothedKeyframe& pub = m_keyframes[first + k].pub;
    pub.smoothedPose = p.poses[k];
    if (!pub.optimised)
    {
      pub.optimised = true;
      // Frames given by now, counted from the keyframe's own frame.
      m_stats.lagFrames.push_back(static_cast<double>(m_given - 1 - pub.frame));
    }
  }
}

std::vector<TSmoothedKeyframe> CKeyframeSmoother::keyframes() const
{
  std::lock_guard<std::mutex> lk(m_mutex);
  std::vector<TSmoothedKeyframe> out;
  out.reserve(m_keyframes.size());
  for (const auto& k : m_keyframes) out.push_back(k.pub);
  return out;
}

core::TTrajectory CKeyframeSmoother::trajectory() const
{
  std::lock_guard<std::mutex> lk(m_mutex);
  core::TTrajectory out;
  out.reserve(m_framePoses.size());
  for (std::size_t i = 0; i < m_framePoses.size(); ++i)
  {
    const std::size_t k = m_frameKeyframe[i] != kNone ? m_frameKeyframe[i] : 0;
    if (m_keyframes.empty())
      out.push_back(m_framePoses[i]);
    else
      out.push_back(carried(m_keyframes[k].pub.smoothedPose, m_keyframes[k].pub.filterPose, m_framePoses[i]));
  }
  return out;
}

TSmootherStats CKeyframeSmoother::stats() const
{
  std::lock_guard<std::mutex> lk(m_mutex);
  return m_stats;
}
}  // namespace immslam::refine
