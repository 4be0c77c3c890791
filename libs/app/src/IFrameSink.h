/* imm-monoslam — private to libs/app: what the frame loop publishes (one TFrameResult a processed
 * frame, the run's end) and the one interface of everything that consumes it (IFrameSink): output
 * files, overlays, scenes, the truth series, the live view, the progress line. */
#pragma once

#include <immslam/app/CImmMonoSlamApp.h>
#include <immslam/io/CImageSource.h>
#include <immslam/system/CHeldBackMatches.h>
#include <immslam/system/CMonoSlamSystem.h>

#include <cstddef>

namespace immslam::app::detail
{
/** One processed frame, as the frame loop publishes it. Valid during IFrameSink::onFrame only. */
struct TFrameResult
{
  std::size_t processed;               ///< frames processed before this one (0: the first)
  const io::TFrame& frame;             ///< index, timestamp, origin, images (after [input] max_image_width)
  const system::TSystemFrame& report;  ///< the system's report of the frame (SLAM, shadow filter, times)
  const slam::CMonoSlamIMM& slam;      ///< the filter after the frame: pose, map, model probabilities
  /** The shadow filter's matches of earlier frames (and this one) whose features became known static
   * with this frame (system::CHeldBackMatches; frame = `processed` of their frame), for the bundle
   * adjustments behind the filter. */
  const std::vector<system::CHeldBackMatches::TMatch>& heldBack;
};

/** A consumer of the frame loop's results. The loop knows only this interface; CRunOutputs decides
 * which writers a run has and in which order they are told. */
class IFrameSink
{
 public:
  virtual ~IFrameSink() = default;
  /** One processed frame. \throws std::runtime_error when an output cannot be written. */
  virtual void onFrame(const TFrameResult& r) = 0;
  /** The end of the run (the input ended, was stopped or --frames reached; also after no frame).
   * A writer may add what it measured to `summary`; writers are told in their order, so a later
   * one reads the figures of an earlier one (the scene reads the ATE). */
  virtual void onEnd(const slam::CMonoSlamIMM& slam, TRunSummary& summary) = 0;
};
}  // namespace immslam::app::detail
