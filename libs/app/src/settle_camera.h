/* imm-monoslam — private to libs/app: the camera of a run settled from its first frame, before the
 * system is built ([input] max_image_width, --fov's guess, a uniformly resampled image of the
 * calibrated camera), and the checks every frame passes (time order, size). */
#pragma once

#include "TImageReduction.h"
#include "run_inputs.h"

#include <atomic>
#include <optional>
#include <string>

namespace immslam::app::detail
{
/** What the first frame settles before the system is built (settleCamera()). */
struct TSettledInput
{
  /** The first frame to process, prepared (reduced); none when the input ended, was stopped or
   * --frames 0 reached before a usable frame. */
  std::optional<io::TFrame> first;
  /** [input] max_image_width, decided at the first frame that passed the time check. */
  TImageReduction reduction;
  /** --fov: TRunInputs::cam was guessed at the first frame's size (written to calib_guessed.txt). */
  bool calibrationGuessed = false;
};

/** Reads the input up to its first usable frame and settles TRunInputs::cam with it:
 * [input] max_image_width reduces the frame (and scales a calibration of the frame's full size),
 * --fov guesses a pinhole camera at the reduced size, a uniformly resampled image of the calibrated
 * camera scales the calibration. Skipped entries on the way (unreadable, out of time order, of
 * another size) are counted in `summary` as the frame loop counts them; the input's end reason
 * too. Nothing is read when `stop` is set or --frames is 0. The frame is kept, not lost: the frame
 * loop processes it first. */
TSettledInput settleCamera(const TRunContext& ctx, TRunInputs& in, TRunSummary& summary,
                           const std::atomic<bool>& stop);

/** Why `frame` cannot follow a frame at time `last` (time must run forward), or "" when it can. */
std::string timeOrderProblem(const io::TFrame& frame, double last);

/** Why `frame` does not fit the camera `cam` (another image size), or "" when it does. */
std::string sizeProblem(const io::TFrame& frame, const camera::CCameraModel& cam);
}  // namespace immslam::app::detail
