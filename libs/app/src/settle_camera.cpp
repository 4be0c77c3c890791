/* imm-monoslam — the camera settled from the first frame (see settle_camera.h). */
#include "settle_camera.h"

#include <immslam/camera/mrpt_camera.h>

#include <cmath>
#include <limits>
#include <sstream>

namespace immslam::app::detail
{
namespace
{
/** [input] max_image_width at the first frame: the reduction, and the camera scaled with it when it
 * is the calibration of the frame's full size. */
TImageReduction decideReduction(const TRunContext& ctx, TRunInputs& in, const io::TFrame& frame)
{
  TImageReduction reduction(frame.grey.size(), in.in.max_image_width);
  if (reduction.factor <= 1) return reduction;
  ctx.log.logStr(mrpt::system::LVL_INFO, reduction.describe(in.in.max_image_width));
  const camera::CCameraModel::Ptr& cam = in.cam;
  if (cam && cam->width() == reduction.full.width && cam->height() == reduction.full.height)
  {
    in.cam = reduction.camera(*cam);
    ctx.log.logStr(mrpt::system::LVL_INFO, "camera (" + in.calibOrigin + ", scaled): " + in.cam->toCalibLine());
  }
  return reduction;
}

/** The frame's size against the calibration: a uniformly resampled image of the calibrated camera
 * scales the calibration (true); any other mismatch skips the frame (false). */
bool fitCamera(const TRunContext& ctx, TRunInputs& in, TRunSummary& summary, const io::TFrame& frame)
{
  const std::string problem = sizeProblem(frame, *in.cam);
  if (problem.empty()) return true;
  const double sx = static_cast<double>(frame.grey.cols) / in.cam->width();
  const double sy = static_cast<double>(frame.grey.rows) / in.cam->height();
  if (std::abs(sx - sy) < 1e-9 && sx > 0)
  {
    ctx.log.logStr(mrpt::system::LVL_WARN, "images are " + std::to_string(frame.grey.cols) + "x" +
                                               std::to_string(frame.grey.rows) +
                                               ": using the calibration scaled by " + std::to_string(sx));
    in.cam = in.cam->scaled(sx);
    return true;
  }
  countSkip(ctx, summary, problem);
  return false;
}
}  // namespace

std::string timeOrderProblem(const io::TFrame& frame, double last)
{
  if (frame.timestamp > last) return std::string();
  // Time must run forward: the motion models integrate over it and the outputs are time series.
  std::ostringstream s;
  s.precision(9);
  s << "frame " << frame.index << " (" << frame.origin << "): timestamp " << frame.timestamp
    << " is not after the previous frame's " << last;
  return s.str();
}

std::string sizeProblem(const io::TFrame& frame, const camera::CCameraModel& cam)
{
  if (frame.grey.cols == cam.width() && frame.grey.rows == cam.height()) return std::string();
  std::ostringstream s;
  s << "frame " << frame.index << " (" << frame.origin << "): image " << frame.grey.cols << "x" << frame.grey.rows
    << " does not match the calibration's " << cam.width() << "x" << cam.height();
  return s.str();
}

TSettledInput settleCamera(const TRunContext& ctx, TRunInputs& in, TRunSummary& summary,
                           const std::atomic<bool>& stop)
{
  TSettledInput out;
  io::TFrame frame;
  std::string why;
  while (!out.first)
  {
    if (stop)
    {
      summary.endReason = "stopped by user";
      break;
    }
    if (ctx.args.maxFrames == 0) break;
    const io::ENextStatus st = in.source->next(frame, why);
    if (st == io::ENextStatus::End)
    {
      summary.endReason = why;
      break;
    }
    ++summary.framesRead;
    const std::string problem =
        st == io::ENextStatus::Skipped ? why : timeOrderProblem(frame, -std::numeric_limits<double>::infinity());
    if (!problem.empty())
    {
      countSkip(ctx, summary, problem);
      continue;
    }
    if (!out.reduction.decided()) out.reduction = decideReduction(ctx, in, frame);
    out.reduction.apply(frame);
    if (in.guessCalibration)
    {
      // The guessed pinhole at this frame's size, kept for a re-run with --calib.
      in.guessCalibration = false;
      out.calibrationGuessed = true;
      in.cam = camera::pinholeFromFieldOfView(frame.grey.cols, frame.grey.rows, ctx.args.fovDeg);
      ctx.log.logStr(mrpt::system::LVL_INFO, "camera (" + in.calibOrigin + "): " + in.cam->toCalibLine());
    }
    if (fitCamera(ctx, in, summary, frame)) out.first = std::move(frame);
  }
  return out;
}
}  // namespace immslam::app::detail
