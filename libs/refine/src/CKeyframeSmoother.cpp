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
// m_placed: no window has placed the keyframe yet / one has / the worker skipped it while behind.
constexpr char kUnplaced = 0, kPlaced = 1, kSkipped = 2;

/** CPU time of the calling thread (seconds). */
double threadCpuSeconds()
{
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

/** Motion-only problem `f` (one pose, points held): removes the measurements whose residual exceeds
 * 3 times the median residual (at least 0.5 px; for a Gaussian error 3.5 sigma, 0.2 % of good
 * measurements), as long as minKept measurements stay. \return whether any was removed. */
bool dropOutlyingMeasurements(TBundleProblem& f, std::size_t minKept)
{
  // One point per measurement (refineFrames()): a point's RMS is its measurement's residual.
  const std::vector<double> res = reprojectionStats(f).featureRmsPx;
  const double limit = std::max(0.5, 3 * eval::median(res));
  std::vector<TBundleObservation> kept;
  for (const auto& o : f.obs)
    if (res[o.point] <= limit) kept.push_back(o);
  if (kept.size() == f.obs.size() || kept.size() < minKept) return false;
  f.obs = std::move(kept);
  return true;
}
}  // namespace

CKeyframeSmoother::CKeyframeSmoother(const TOptions& opts, double fx, double fy) : m_opts(opts), m_fx(fx), m_fy(fy)
{
  if (m_opts.windowKeyframes < 2) throw std::invalid_argument("CKeyframeSmoother: windowKeyframes must be >= 2");
  if (!(m_opts.gaugeBaselinePx > 0)) throw std::invalid_argument("CKeyframeSmoother: gaugeBaselinePx must be > 0");
  if (m_opts.minViews < 2) throw std::invalid_argument("CKeyframeSmoother: minViews must be >= 2");
  if (m_opts.windowEvery < 1) throw std::invalid_argument("CKeyframeSmoother: windowEvery must be >= 1");
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
  {
    std::lock_guard<std::mutex> lk(m_mutex);
    for (const auto& pm : frame.past)
      if (pm.first > m_given)  // m_given: this frame's index
        throw std::logic_error("CKeyframeSmoother::addFrame: a past match of a frame not given yet");
  }
  if (m_opts.synchronous)
  {
    if (m_finished) throw std::logic_error("CKeyframeSmoother::addFrame after finish()");
    const double c0 = threadCpuSeconds();
    {
      std::lock_guard<std::mutex> lk(m_mutex);
      ++m_given;
    }
    step(std::move(frame), 0);
    std::lock_guard<std::mutex> lk(m_mutex);
    m_stats.cpuSeconds += threadCpuSeconds() - c0;
    return;
  }
  {
    std::unique_lock<std::mutex> lk(m_mutex);
    if (m_stop) throw std::logic_error("CKeyframeSmoother::addFrame after finish()");
    // A recorded input may wait for the worker: it never falls behind, so it never skips a window.
    if (m_opts.waitWhenBehind) m_room.wait(lk, [&] { return m_queue.size() < std::max<std::size_t>(1, m_opts.maxBacklogFrames); });
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
      m_room.notify_one();
      backlog = m_queue.size();
    }
    step(std::move(frame), backlog);
    std::lock_guard<std::mutex> lk(m_mutex);
    m_stats.cpuSeconds = threadCpuSeconds() - c0;
  }
  if (m_keyframesSinceWindow > 0) optimiseWindow();
  std::lock_guard<std::mutex> lk(m_mutex);
  m_stats.cpuSeconds = threadCpuSeconds() - c0;
}

void CKeyframeSmoother::step(TSmootherFrame&& frame, std::size_t backlog)
{
  // Frames are taken one by one and the window optimised at every windowEvery-th keyframe, as in a
  // synchronous run (same result), unless the worker is behind by more than maxBacklogFrames: then
  // the optimisation is left to a later frame (the lag stays bounded, the filter never waits).
  const bool newKeyframe = ingest(std::move(frame));
  m_keyframesSinceWindow += newKeyframe ? 1 : 0;
  if (m_keyframesSinceWindow >= m_opts.windowEvery && backlog <= m_opts.maxBacklogFrames)
  {
    optimiseWindow();
    m_keyframesSinceWindow = 0;
  }
  else if (newKeyframe && backlog > m_opts.maxBacklogFrames)
  {
    std::lock_guard<std::mutex> lk(m_mutex);
    m_placed.back() = kSkipped;
  }
}

void CKeyframeSmoother::finish()
{
  if (m_opts.synchronous)
  {
    if (m_finished) return;
    m_finished = true;
    const double c0 = threadCpuSeconds();
    if (m_keyframesSinceWindow > 0) optimiseWindow();
    m_keyframesSinceWindow = 0;
    std::lock_guard<std::mutex> lk(m_mutex);
    m_stats.cpuSeconds += threadCpuSeconds() - c0;
    return;
  }
  {
    std::lock_guard<std::mutex> lk(m_mutex);
    m_stop = true;
  }
  m_wake.notify_one();
  if (m_thread.joinable()) m_thread.join();
}

std::vector<double> CKeyframeSmoother::parallaxPx(const core::TStampedPose& poseA, const std::vector<TSmootherMatch>& a,
                                              const core::TStampedPose& poseB, const std::vector<TSmootherMatch>& b) const
{
  // Chain rule of the bearings: b_B = R_B_W R_W_A b_A for a point at infinity (no parallax).
  const Mat3 R_B_A = math::quatToRotation(poseB.q_W_C).transpose() * math::quatToRotation(poseA.q_W_C);
  std::unordered_map<std::int64_t, Vec2> atA;
  for (const auto& m : a) atA.emplace(m.featureId, m.xn);
  std::vector<double> out;
  for (const auto& m : b)
  {
    const auto it = atA.find(m.featureId);
    if (it == atA.end()) continue;
    const Vec3 r = R_B_A * Vec3(it->second.x(), it->second.y(), 1);
    if (!(r.z() > 0)) continue;
    out.push_back(std::hypot(m_fx * (m.xn.x() - r.x() / r.z()), m_fy * (m.xn.y() - r.y() / r.z())));
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
      const TSmoothedKeyframe& last = m_keyframes.back();
      const std::vector<double> parallax =
          parallaxPx(last.filterPose, m_frameMatches[last.frame], frame.pose, frame.matches);
      isKeyframe = parallax.size() < m_opts.minMatches || eval::median(parallax) >= m_opts.minParallaxPx;
    }
  }
  std::lock_guard<std::mutex> lk(m_mutex);
  m_framePoses.push_back(frame.pose);
  m_frameMatches.push_back(std::move(frame.matches));
  // The matches that came late, into their frames (this one's too: after the choice of keyframes).
  for (const auto& [at, m] : frame.past)
  {
    auto& ms = m_frameMatches[at];
    if (std::none_of(ms.begin(), ms.end(), [&](const TSmootherMatch& o) { return o.featureId == m.featureId; }))
      ms.push_back(m);
  }
  m_frameRefined.emplace_back();
  ++m_stats.frames;
  if (!isKeyframe)
  {
    m_frameKeyframe.push_back(m_keyframes.empty() ? kNone : m_keyframes.size() - 1);
    return false;
  }
  TSmoothedKeyframe kf;
  kf.frame = index;
  kf.filterPose = frame.pose;
  // Starts where the last keyframe's smoothed pose and the filter's motion since it put it.
  kf.smoothedPose = m_keyframes.empty()
                        ? frame.pose
                        : core::carryPose(m_keyframes.back().smoothedPose, m_keyframes.back().filterPose, frame.pose);
  m_frameKeyframe.push_back(m_keyframes.size());
  m_keyframes.push_back(kf);
  m_placed.push_back(kUnplaced);
  ++m_stats.keyframes;
  return true;
}

std::size_t CKeyframeSmoother::gaugeKeyframe(std::size_t first, std::size_t n) const
{
  const TSmoothedKeyframe& newest = m_keyframes[first + n - 1];
  for (std::size_t k = 0; k + 1 < n; ++k)
  {
    const TSmoothedKeyframe& kf = m_keyframes[first + k];
    const std::vector<double> par =
        parallaxPx(kf.filterPose, m_frameMatches[kf.frame], newest.filterPose, m_frameMatches[newest.frame]);
    if (par.size() >= m_opts.minMatches && eval::median(par) >= m_opts.gaugeBaselinePx) return k;
  }
  return kNone;
}

std::size_t CKeyframeSmoother::knownDepths(std::size_t first, std::size_t n) const
{
  std::size_t count = 0;
  for (std::size_t k = 0; k < n; ++k)
    for (const auto& m : m_frameMatches[m_keyframes[first + k].frame])
      count += m.depthRelSigma <= m_opts.startDepthRelSigma ? 1 : 0;
  return count;
}

TBundleProblem CKeyframeSmoother::windowProblem(std::size_t first, std::size_t n, std::vector<std::size_t>& anchors) const
{
  // The window's features, and the keyframes before the window that measured them (the anchors,
  // newest first, at most anchorKeyframes of them): held at their smoothed poses, they tie the
  // window to the map the earlier windows placed, its frame and scale included, so a feature seen
  // again is not placed anew.
  std::map<std::int64_t, std::vector<TBundleObservation>> byFeature;
  for (std::size_t k = 0; k < n; ++k)
    for (const auto& m : m_frameMatches[m_keyframes[first + k].frame]) byFeature[m.featureId].push_back({k, 0, m.xn});
  anchors.clear();
  for (std::size_t j = first; j-- > 0 && anchors.size() < m_opts.anchorKeyframes;)
  {
    // A keyframe the worker skipped while behind and no window has placed since: the window is
    // tied to the map before it only through poses the filter's motion carried, so it holds its own
    // gauge (continuing them) rather than anchors across the gap.
    if (m_placed[j] == kSkipped) break;
    if (m_placed[j] != kPlaced) continue;  // no window yet (it waited for a gauge): the filter's pose, carried
    const auto& matches = m_frameMatches[m_keyframes[j].frame];
    if (std::any_of(matches.begin(), matches.end(), [&](const TSmootherMatch& m) { return byFeature.count(m.featureId); }))
      anchors.push_back(j);
  }
  // The problem: the window's keyframes (0..n-1), then the anchors; the features measured by
  // minViews of them, triangulated from the current poses.
  TBundleProblem p;
  p.fx = m_fx;
  p.fy = m_fy;
  for (std::size_t k = 0; k < n; ++k) p.poses.push_back(m_keyframes[first + k].smoothedPose);
  for (std::size_t a = 0; a < anchors.size(); ++a)
  {
    p.poses.push_back(m_keyframes[anchors[a]].smoothedPose);
    for (const auto& m : m_frameMatches[m_keyframes[anchors[a]].frame])
    {
      const auto it = byFeature.find(m.featureId);
      if (it != byFeature.end()) it->second.push_back({n + a, 0, m.xn});
    }
  }
  for (auto& [id, obs] : byFeature)
  {
    if (static_cast<int>(obs.size()) < m_opts.minViews) continue;
    for (auto& o : obs) o.point = p.featureIds.size();
    p.featureIds.push_back(id);
    p.obs.insert(p.obs.end(), obs.begin(), obs.end());
  }
  p.points.assign(p.featureIds.size(), Vec3::Zero());
  if (!p.featureIds.empty()) triangulateAll(p);
  return p;
}

void CKeyframeSmoother::optimiseWindow()
{
  // The window: the newest windowKeyframes keyframes, and back to the oldest keyframe no window has
  // placed yet (a worker that skipped windows catches up on them, up to twice the window); until
  // one window has been optimised, every keyframe so far (none is left out of the smoothing while
  // the gauge waits for a baseline).
  std::size_t unplaced = 0;  // keyframes since the newest placed one
  while (unplaced < m_keyframes.size() && m_placed[m_keyframes.size() - 1 - unplaced] != kPlaced) ++unplaced;
  bool isLong = false;
  std::size_t n = m_stats.optimisations == 0
                      ? m_keyframes.size()
                      : std::min(m_keyframes.size(),
                                 std::max(m_opts.windowKeyframes, std::min(unplaced + 1, 2 * m_opts.windowKeyframes)));
  // A long window now and then: the short windows never move a keyframe once it anchors them, and a
  // drift that builds up slowly over hundreds of frames stays in their poses.
  if (m_opts.longWindowEvery > 0 && m_stats.optimisations > 0 &&
      m_keyframes.size() >= m_longWindowAt + m_opts.longWindowEvery)
  {
    n = std::max(n, std::min(m_keyframes.size(), m_opts.longWindowKeyframes));
    m_longWindowAt = m_keyframes.size();
    isLong = true;
  }
  if (n < 2) return;
  const std::size_t first = m_keyframes.size() - n;
  std::vector<std::size_t> anchors;
  TBundleProblem p = windowProblem(first, n, anchors);
  if (p.featureIds.empty()) return;
  // Without two anchors (the run's first windows, a new map after a loss) the window holds its own
  // gauge: its earliest keyframe that sees the newest one with gaugeBaselinePx of parallax is held,
  // and the distance between the two stays as the keyframes' current poses have it (the scale
  // continues the smoothed poses before, or the filter's at the start). Only the scale is taken
  // from those poses: the direction of the baseline and every other pose are the images'.
  std::size_t held = kNone;
  if (anchors.size() < 2)
  {
    held = gaugeKeyframe(first, n);
    if (held == kNone) return;  // no baseline yet: the images cannot fix the window's scale
    // The run's first window waits (up to twice its size) for the filter's converged depths: until
    // the filter has seen the camera move, its motion gives the gauge pair no distance.
    if (m_opts.startDepthRelSigma > 0 && m_stats.optimisations == 0 && n < 2 * m_opts.windowKeyframes &&
        knownDepths(first, n) < m_opts.minMatches)
      return;
  }

  TBundleOptions bo;
  bo.huberPx = m_opts.huberPx;
  bo.maxIterations = m_opts.maxIterations;
  bo.outlierIterations = 10;  // the outlier pass's second solve starts near its minimum
  if (anchors.size() < 2) bo.maxIterations = m_opts.gaugeMaxIterations;
  // A long window starts from the poses the short windows placed (and those of the run's start too).
  if (isLong) bo.maxIterations = m_opts.longWindowMaxIterations;
  for (std::size_t a = 0; a < anchors.size(); ++a) bo.heldPoses.push_back(n + a);
  if (held != kNone)
  {
    bo.heldPoses.push_back(held);
    bo.scalePoses = {held, n - 1};
  }
  const bool converged = bundleAdjust(p, bo).converged;

  {
    std::lock_guard<std::mutex> lk(m_mutex);
    ++m_stats.optimisations;
    m_stats.unconverged += converged ? 0 : 1;
    m_optimisedOnce = true;
    for (std::size_t k = 0; k < n; ++k)
    {
      m_placed[first + k] = kPlaced;
      if (k == held) continue;
      TSmoothedKeyframe& kf = m_keyframes[first + k];
      kf.smoothedPose = p.poses[k];
      if (!kf.optimised)
      {
        kf.optimised = true;
        // Frames given by now, counted from the keyframe's own frame.
        m_stats.lagFrames.push_back(static_cast<double>(m_given - 1 - kf.frame));
      }
    }
  }
  refineFrames(m_keyframes[first].frame, p);
}

void CKeyframeSmoother::refineFrames(std::size_t firstFrame, const TBundleProblem& window)
{
  // Motion-only: each frame between keyframes refined against the window's points, held (the frame
  // measures them; its pose alone is free), from its keyframe's pose and the filter's motion since.
  std::unordered_map<std::int64_t, std::size_t> pointOf;
  for (std::size_t j = 0; j < window.featureIds.size(); ++j) pointOf.emplace(window.featureIds[j], j);
  const std::size_t nFrames = m_framePoses.size();
  for (std::size_t i = firstFrame; i < nFrames; ++i)
  {
    const std::size_t k = m_frameKeyframe[i];
    if (k == kNone || m_keyframes[k].frame == i) continue;  // a keyframe: the window placed it
    TBundleProblem f;
    f.fx = window.fx;
    f.fy = window.fy;
    f.poses.push_back(composedPose(i));
    for (const auto& m : m_frameMatches[i])
    {
      const auto it = pointOf.find(m.featureId);
      if (it == pointOf.end()) continue;
      f.obs.push_back({0, f.points.size(), m.xn});
      f.points.push_back(window.points[it->second]);
    }
    if (f.obs.size() < m_opts.minMatches) continue;
    TBundleOptions bo;
    bo.huberPx = m_opts.huberPx;
    bo.maxIterations = 10;
    bo.holdPoints = true;
    bo.outlierFactor = 0;  // one pose: its own pass below, which keeps minMatches measurements
    const core::TStampedPose start = f.poses[0];
    bundleAdjust(f, bo);
    // One frame's pose rests on a few dozen points: a single one the window placed badly (a point
    // its keyframes measured some pixels from where this frame sees it) can still pull it along the
    // direction the others determine least, Huber cost or not. Measurements far outside the
    // frame's own residual spread are left out and the frame refined again.
    if (dropOutlyingMeasurements(f, m_opts.minMatches))
    {
      f.poses[0] = start;
      bundleAdjust(f, bo);
    }
    std::lock_guard<std::mutex> lk(m_mutex);
    m_frameRefined[i] = f.poses[0];
  }
}

std::vector<TSmoothedKeyframe> CKeyframeSmoother::keyframes() const
{
  std::lock_guard<std::mutex> lk(m_mutex);
  return m_keyframes;
}

core::TTrajectory CKeyframeSmoother::trajectory() const
{
  std::lock_guard<std::mutex> lk(m_mutex);
  core::TTrajectory out;
  out.reserve(m_framePoses.size());
  for (std::size_t i = 0; i < m_framePoses.size(); ++i) out.push_back(m_frameRefined[i].value_or(composedPose(i)));
  // A frame with fewer than minMatches matches is not placed by the images (the filter lost its
  // features: a fast turn, blur, an occlusion), and the filter's pose there is a prediction
  // corrected by a match or two. Between two frames with matches it takes the pose interpolated in
  // time: a smoother has the frames after it.
  std::size_t last = kNone;  // the last frame with minMatches matches
  for (std::size_t i = 0; i < out.size(); ++i)
  {
    if (m_frameMatches[i].size() < m_opts.minMatches) continue;
    if (last != kNone)
      for (std::size_t j = last + 1; j < i; ++j) out[j] = core::interpolatePose(out[last], out[i], out[j].timestamp);
    last = i;
  }
  return out;
}

core::TStampedPose CKeyframeSmoother::composedPose(std::size_t i) const
{
  if (m_keyframes.empty()) return m_framePoses[i];
  const TSmoothedKeyframe& kf = m_keyframes[m_frameKeyframe[i] != kNone ? m_frameKeyframe[i] : 0];
  return core::carryPose(kf.smoothedPose, kf.filterPose, m_framePoses[i]);
}

TSmootherStats CKeyframeSmoother::stats() const
{
  std::lock_guard<std::mutex> lk(m_mutex);
  return m_stats;
}
}  // namespace immslam::refine
