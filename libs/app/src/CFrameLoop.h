/* imm-monoslam — private to libs/app: the frame loop of a run: read, check and prepare each frame,
 * run the system on it, hand the result to the outputs, show the progress. */
#pragma once

#include <immslam/app/CImmMonoSlamApp.h>
#include <immslam/system/CMonoSlamSystem.h>

#include "CRunOutputs.h"
#include "TImageReduction.h"
#include "run_inputs.h"

#include <atomic>
#include <chrono>
#include <limits>
#include <memory>
#include <string>

namespace immslam::app::detail
{
/** Owns the system (CMonoSlamSystem) of a run and runs it over the input's frames. The first frame
 * may still change the camera, and with it the system: [input] max_image_width, --fov's guess at the
 * frame's size, a uniformly resampled image of the calibrated camera. */
class CFrameLoop
{
 public:
  /** Builds the system for the inputs' camera. \throws std::runtime_error prefixed by the config file
   * for a bad [system], [slam], [shadow]... section. */
  CFrameLoop(const TRunContext& ctx, TRunInputs& in, TRunSummary& summary);

  /** The system (valid until the next frame may rebuild it). */
  const system::CMonoSlamSystem& system() const { return *m_sys; }

  /** Reads frames until the end of the input, `stop` or --frames; every processed frame goes to
   * `outputs`, every skipped one is counted (and logged, the first few) in the summary. Then closes
   * the --record rawlog and sets the summary's wall time.
   * \throws std::runtime_error naming the frame when the system or its exclusion mask fails. */
  void run(CRunOutputs& outputs, const std::atomic<bool>& stop);

 private:
  using Clock = std::chrono::steady_clock;

  /** Checks and prepares a frame read from the input: time order, [input] max_image_width, --fov's
   * guess, size against the calibration. False (skip() called) when it cannot be processed. */
  bool prepare(io::TFrame& frame, const CRunOutputs& outputs);
  /** [input] max_image_width at the first frame: the reduction, and the camera scaled with it. */
  void decideReduction(const io::TFrame& frame);
  /** The frame's size against the calibration: a uniformly resampled first frame scales the camera;
   * any other mismatch skips the frame (false). */
  bool checkSize(const io::TFrame& frame);
  /** The system on one frame: its images with the exclusion mask, or the known tracks at its time. */
  const system::TSystemFrame& process(const io::TFrame& frame);
  /** Counts a skipped entry; the first few reasons are logged and kept in the summary. */
  void skip(const std::string& reason);
  /** The progress line on a terminal, at most every 0.2 s. */
  void showProgress(const system::TSystemFrame& fr);
  /** The system rebuilt for a new camera (same configuration). */
  void rebuildSystem();

  const TRunContext& m_ctx;
  TRunInputs& m_in;
  TRunSummary& m_summary;
  std::unique_ptr<system::CMonoSlamSystem> m_sys;
  TImageReduction m_reduction;  ///< [input] max_image_width, decided at the first frame
  double m_lastTimestamp = -std::numeric_limits<double>::infinity();
  bool m_tty = false;           ///< progress line on stderr
  std::size_t m_total = 0;      ///< the source's size hint
  Clock::time_point m_start, m_lastProgress;
};
}  // namespace immslam::app::detail
