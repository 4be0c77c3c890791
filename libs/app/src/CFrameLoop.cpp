/* imm-monoslam — the frame loop of a run (see CFrameLoop.h). */
#include "CFrameLoop.h"

#include "settle_camera.h"

#include <immslam/io/CRawlogRecorder.h>

#include <sstream>
#include <stdexcept>

namespace immslam::app::detail
{
namespace
{
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
}  // namespace

CFrameLoop::CFrameLoop(const TRunContext& ctx, const TRunInputs& in, system::CMonoSlamSystem& sys,
                       const TImageReduction& reduction, TRunSummary& summary)
    : m_ctx(ctx), m_in(in), m_sys(sys), m_reduction(reduction), m_summary(summary)
{
}

void CFrameLoop::run(std::optional<io::TFrame> first, const std::vector<IFrameSink*>& sinks,
                     const std::atomic<bool>& stop)
{
  const Clock::time_point start = Clock::now();
  if (first)
  {
    publish(*first, sinks);
    first.reset();
    io::TFrame frame;
    while (nextFrame(frame, stop)) publish(frame, sinks);
  }
  if (m_in.recorder) m_in.recorder->close();
  m_summary.wallSeconds = std::chrono::duration<double>(Clock::now() - start).count();
  for (IFrameSink* s : sinks) s->onEnd(m_sys.slam(), m_summary);
}

bool CFrameLoop::nextFrame(io::TFrame& frame, const std::atomic<bool>& stop)
{
  std::string why;
  for (;;)
  {
    if (stop)
    {
      m_summary.endReason = "stopped by user";
      return false;
    }
    if (m_ctx.args.maxFrames >= 0 && static_cast<long long>(m_summary.framesProcessed) >= m_ctx.args.maxFrames)
      return false;
    const io::ENextStatus st = m_in.source->next(frame, why);
    if (st == io::ENextStatus::End)
    {
      m_summary.endReason = why;
      return false;
    }
    ++m_summary.framesRead;
    std::string problem = st == io::ENextStatus::Skipped ? why : timeOrderProblem(frame, m_lastTimestamp);
    if (problem.empty())
    {
      m_reduction.apply(frame);
      problem = sizeProblem(frame, *m_in.cam);
    }
    if (problem.empty()) return true;
    countSkip(m_ctx, m_summary, problem);
  }
}

void CFrameLoop::publish(const io::TFrame& frame, const std::vector<IFrameSink*>& sinks)
{
  const system::TSystemFrame& fr = process(frame);
  const std::vector<system::CHeldBackMatches::TMatch> heldBack =
      m_heldBack.update(m_summary.framesProcessed, fr.shadow, m_sys.slam());
  const TFrameResult result{m_summary.framesProcessed, frame, fr, m_sys.slam(), heldBack};
  for (IFrameSink* s : sinks) s->onFrame(result);
  ++m_summary.framesProcessed;
  m_lastTimestamp = frame.timestamp;
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
    if (!m_in.knownTracks) return m_sys.processFrame(frame.timestamp, frame.grey, excluded);
    const bool staticOnly = m_summary.framesProcessed == 0 && m_in.in.known_association_first_map == "static";
    const auto z = m_in.knownTracks->at(frame.timestamp, m_reduction.factor, staticOnly);
    if (z.empty() && m_summary.framesWithoutTracks++ == 0)
      m_ctx.log.logStr(mrpt::system::LVL_WARN, "frame " + std::to_string(frame.index) + " (" + frame.origin +
                                                   "): no track of [input] known_association at its timestamp");
    return m_sys.processMeasurements(frame.timestamp, z, m_in.in.known_association_robust);
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error("frame " + std::to_string(frame.index) + " (" + frame.origin + "): " + e.what());
  }
}
}  // namespace immslam::app::detail
