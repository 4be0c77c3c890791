/* imm-monoslam — private to libs/app: the frame loop of a run: read and check each frame, run the
 * system on it, publish the result to the run's writers (IFrameSink). */
#pragma once

#include <immslam/app/CImmMonoSlamApp.h>
#include <immslam/system/CMonoSlamSystem.h>

#include "IFrameSink.h"
#include "TImageReduction.h"
#include "run_inputs.h"

#include <atomic>
#include <chrono>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace immslam::app::detail
{
/** Runs the system of a run over the input's frames and publishes each processed frame to the
 * writers. The camera is settled before (settleCamera()): the loop never changes the system. */
class CFrameLoop
{
 public:
  /** \param sys the system, built once for the settled camera TRunInputs::cam.
   * \param reduction [input] max_image_width as the first frame decided it. */
  CFrameLoop(const TRunContext& ctx, const TRunInputs& in, system::CMonoSlamSystem& sys,
             const TImageReduction& reduction, TRunSummary& summary);

  /** Processes `first` (the frame settleCamera() kept; none: the input gave no usable frame), then
   * reads frames until the end of the input, `stop` or --frames; every processed frame goes to each
   * of `sinks` in order, every skipped one is counted in the summary. Then closes the --record
   * rawlog, sets the summary's wall time and tells the sinks the run's end.
   * \throws std::runtime_error naming the frame when the system or its exclusion mask fails. */
  void run(std::optional<io::TFrame> first, const std::vector<IFrameSink*>& sinks, const std::atomic<bool>& stop);

 private:
  using Clock = std::chrono::steady_clock;

  /** Reads up to the next frame that passes the checks (time order, size; reduced first). False at
   * the end of the input, at `stop` or at --frames (the summary's end reason set). */
  bool nextFrame(io::TFrame& frame, const std::atomic<bool>& stop);
  /** The system on one frame: its images with the exclusion mask, or the known tracks at its time. */
  const system::TSystemFrame& process(const io::TFrame& frame);
  /** Processes a frame and publishes its result. */
  void publish(const io::TFrame& frame, const std::vector<IFrameSink*>& sinks);

  const TRunContext& m_ctx;
  const TRunInputs& m_in;
  system::CMonoSlamSystem& m_sys;
  const TImageReduction m_reduction;
  TRunSummary& m_summary;
  double m_lastTimestamp = -std::numeric_limits<double>::infinity();
  /** The shadow filter's matches of features not yet known static (TFrameResult::heldBack). */
  system::CHeldBackMatches m_heldBack;
};
}  // namespace immslam::app::detail
