/* imm-monoslam — the frame loop of a run (see CFrameLoop.h). */
#include "CFrameLoop.h"

#include <immslam/camera/mrpt_camera.h>
#include <immslam/io/CRawlogRecorder.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace immslam::app::detail
{
namespace
{
/** Skipped entries logged one by one (and kept in TRunSummary::skipReasons); the rest are counted. */
constexpr std::size_t kLoggedSkips = 20;

/** [input] exclusion_masks: the mask of a frame (non-zero: excluded) at the processed image size, or
 * an empty image when the folder has none for the frame's timestamp.
 * \throws std::runtime_error naming the frame and the key for a mask of another size. */
cv::Mat exclusionMaskFor(const eval::TMaskProvider& maskAt, const io::TFrame& frame, const TImageReduction& reduction)
{
  const std::optional<eval::TMaskImage> m = maskAt(frame.timestamp);
  if (!m) return cv::Mat();
  cv::Mat mask(m->height, m->width, CV_8UC1, const_cast<std::uint8_t*>(m->pixels.data()));
  mask = reduction.applyToMask(mask != 0);
  if (mask.size() != frame.grey.size())
  {
    const cv::Size image = reduction.factor > 1 ? reduction.full : frame.grey.size();
    std::ostringstream s;
    s << "frame " << frame.index << " (" << frame.origin << "): [input] exclusion_masks: mask of " << m->width << "x"
      << m->height << " pixels for an image of " << image.width << "x" << image.height;
    throw std::runtime_error(s.str());
  }
  return mask;
}

std::string formatSeconds(double s)
{
  std::ostringstream o;
  if (s >= 60)
    o << static_cast<int>(s / 60) << "m" << std::setw(2) << std::setfill('0') << static_cast<int>(s) % 60 << "s";
  else
    o << std::fixed << std::setprecision(0) << s << "s";
  return o.str();
}
}  // namespace

CFrameLoop::CFrameLoop(const TRunContext& ctx, TRunInputs& in, TRunSummary& summary)
    : m_ctx(ctx), m_in(in), m_summary(summary)
{
  try
  {
    m_sys = std::make_unique<system::CMonoSlamSystem>(ctx.cfg, in.cam);
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error(ctx.args.config + ": " + e.what());
  }
}

void CFrameLoop::rebuildSystem() { m_sys = std::make_unique<system::CMonoSlamSystem>(m_ctx.cfg, m_in.cam); }

void CFrameLoop::run(CRunOutputs& outputs, const std::atomic<bool>& stop)
{
  m_tty = !m_ctx.args.quiet && isatty(fileno(stderr));
  m_total = m_in.source->sizeHint();
  m_start = Clock::now();
  m_lastProgress = m_start;
  io::TFrame frame;
  std::string why;
  for (;;)
  {
    if (stop)
    {
      m_summary.endReason = "stopped by user";
      break;
    }
    if (m_ctx.args.maxFrames >= 0 && static_cast<long long>(m_summary.framesProcessed) >= m_ctx.args.maxFrames) break;
    const io::ENextStatus st = m_in.source->next(frame, why);
    if (st == io::ENextStatus::End)
    {
      m_summary.endReason = why;
      break;
    }
    ++m_summary.framesRead;
    if (st == io::ENextStatus::Skipped)
    {
      skip(why);
      continue;
    }
    if (!prepare(frame, outputs)) continue;
    const system::TSystemFrame& fr = process(frame);
    outputs.addFrame(m_summary.framesProcessed, frame, fr, m_sys->slam());
    ++m_summary.framesProcessed;
    m_lastTimestamp = frame.timestamp;
    if (m_tty) showProgress(fr);
  }
  if (m_tty) std::fprintf(stderr, "\n");
  if (m_in.recorder) m_in.recorder->close();
  m_summary.wallSeconds = std::chrono::duration<double>(Clock::now() - m_start).count();
}

void CFrameLoop::skip(const std::string& reason)
{
  ++m_summary.framesSkipped;
  // The first kLoggedSkips reasons are logged and kept; a rawlog of many sensors (IMU at 200 Hz, a second
  // camera) would otherwise bury the log: the rest are counted (summary line).
  if (m_summary.skipReasons.size() < kLoggedSkips)
  {
    m_summary.skipReasons.push_back(reason);
    m_ctx.log.logStr(mrpt::system::LVL_WARN, "skipped: " + reason);
    if (m_summary.skipReasons.size() == kLoggedSkips)
      m_ctx.log.logStr(mrpt::system::LVL_WARN, "further skipped entries are counted, not logged");
  }
}

bool CFrameLoop::prepare(io::TFrame& frame, const CRunOutputs& outputs)
{
  if (!(frame.timestamp > m_lastTimestamp))
  {
    // Time must run forward: the motion models integrate over it and the outputs are time series.
    std::ostringstream s;
    s.precision(9);
    s << "frame " << frame.index << " (" << frame.origin << "): timestamp " << frame.timestamp
      << " is not after the previous frame's " << m_lastTimestamp;
    skip(s.str());
    return false;
  }
  if (m_summary.framesProcessed == 0 && !m_reduction.decided()) decideReduction(frame);
  m_reduction.apply(frame);
  if (m_in.guessCalibration)
  {
    // The guessed pinhole at this frame's size, kept for a re-run with --calib.
    m_in.guessCalibration = false;
    m_in.cam = camera::pinholeFromFieldOfView(frame.grey.cols, frame.grey.rows, m_ctx.args.fovDeg);
    rebuildSystem();
    camera::saveCalibFile(*m_in.cam, outputs.files().path("calib_guessed.txt"));
    m_ctx.log.logStr(mrpt::system::LVL_INFO, "camera (" + m_in.calibOrigin + "): " + m_in.cam->toCalibLine());
  }
  return checkSize(frame);
}

void CFrameLoop::decideReduction(const io::TFrame& frame)
{
  m_reduction = TImageReduction(frame.grey.size(), m_in.in.max_image_width);
  if (m_reduction.factor <= 1) return;
  m_ctx.log.logStr(mrpt::system::LVL_INFO, m_reduction.describe(m_in.in.max_image_width));
  const camera::CCameraModel::Ptr& cam = m_in.cam;
  if (cam && cam->width() == m_reduction.full.width && cam->height() == m_reduction.full.height)
  {
    m_in.cam = m_reduction.camera(*cam);
    rebuildSystem();
    m_ctx.log.logStr(mrpt::system::LVL_INFO,
                     "camera (" + m_in.calibOrigin + ", scaled): " + m_in.cam->toCalibLine());
  }
}

bool CFrameLoop::checkSize(const io::TFrame& frame)
{
  const camera::CCameraModel::Ptr& cam = m_in.cam;
  if (frame.grey.cols == cam->width() && frame.grey.rows == cam->height()) return true;
  // A uniformly resampled image of the calibrated camera is accepted with the scaled model.
  const double sx = static_cast<double>(frame.grey.cols) / cam->width();
  const double sy = static_cast<double>(frame.grey.rows) / cam->height();
  if (m_summary.framesProcessed == 0 && std::abs(sx - sy) < 1e-9 && sx > 0)
  {
    m_ctx.log.logStr(mrpt::system::LVL_WARN, "images are " + std::to_string(frame.grey.cols) + "x" +
                                                 std::to_string(frame.grey.rows) +
                                                 ": using the calibration scaled by " + std::to_string(sx));
    m_in.cam = cam->scaled(sx);
    rebuildSystem();
    return true;
  }
  std::ostringstream s;
  s << "frame " << frame.index << " (" << frame.origin << "): image " << frame.grey.cols << "x" << frame.grey.rows
    << " does not match the calibration's " << cam->width() << "x" << cam->height();
  skip(s.str());
  return false;
}

const system::TSystemFrame& CFrameLoop::process(const io::TFrame& frame)
{
  cv::Mat excluded;
  if (m_in.excludedAt)
  {
    excluded = exclusionMaskFor(m_in.excludedAt, frame, m_reduction);
    if (excluded.empty() && m_summary.framesWithoutMask++ == 0)
      m_ctx.log.logStr(mrpt::system::LVL_WARN, "frame " + std::to_string(frame.index) + " (" + frame.origin +
                                                   "): no exclusion mask for its timestamp; such frames exclude nothing");
  }
  try
  {
    if (!m_in.knownTracks) return m_sys->processFrame(frame.timestamp, frame.grey, excluded);
    const bool staticOnly = m_summary.framesProcessed == 0 && m_in.in.known_association_first_map == "static";
    const auto z = m_in.knownTracks->at(frame.timestamp, m_reduction.factor, staticOnly);
    if (z.empty() && m_summary.framesWithoutTracks++ == 0)
      m_ctx.log.logStr(mrpt::system::LVL_WARN, "frame " + std::to_string(frame.index) + " (" + frame.origin +
                                                   "): no track of [input] known_association at its timestamp");
    return m_sys->processMeasurements(frame.timestamp, z, m_in.in.known_association_robust);
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error("frame " + std::to_string(frame.index) + " (" + frame.origin + "): " + e.what());
  }
}

void CFrameLoop::showProgress(const system::TSystemFrame& fr)
{
  if (std::chrono::duration<double>(Clock::now() - m_lastProgress).count() <= 0.2) return;
  m_lastProgress = Clock::now();
  const double el = std::chrono::duration<double>(m_lastProgress - m_start).count();
  const double fps = m_summary.framesProcessed / std::max(el, 1e-9);
  const VecX mu = m_sys->slam().modelProbabilities();
  int best = 0;
  mu.maxCoeff(&best);
  std::fprintf(stderr, "\rframe %zu%s  %.1f fps  map %d  matched %d  %s %.2f", m_summary.framesRead,
               m_total ? ("/" + std::to_string(m_total)).c_str() : "", fps, fr.slam->nMap, fr.slam->nMatched,
               m_sys->slam().models()[best].name.c_str(), mu[best]);
  if (m_total > m_summary.framesRead)
    std::fprintf(stderr, "  ETA %s", formatSeconds((m_total - m_summary.framesRead) / std::max(fps, 1e-9)).c_str());
  std::fprintf(stderr, "   ");
}
}  // namespace immslam::app::detail
