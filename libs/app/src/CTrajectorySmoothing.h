/* imm-monoslam — private to libs/app: [output] smooth_trajectory, the online keyframe smoother
 * (refine::CKeyframeSmoother) fed with every frame's pose and the matches of its update, and
 * trajectory_smoothed.txt written at the end with its ATE, lag and CPU share. */
#pragma once

#include <immslam/app/CImmMonoSlamApp.h>
#include <immslam/camera/CCameraModel.h>
#include <immslam/refine/CKeyframeSmoother.h>
#include <immslam/system/CHeldBackMatches.h>
#include <immslam/system/CMonoSlamSystem.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace immslam::app::detail
{
/** Feeds the smoother (its own thread: the frame loop only hands data over) and writes its output. */
class CTrajectorySmoothing
{
 public:
  /** \param cam the camera that undistorts the matched pixels (kept by reference).
   * \param live a live camera: the smoother skips windows when behind; otherwise (recorded input)
   *        the run waits for it (refine::CKeyframeSmoother::TOptions::waitWhenBehind). */
  CTrajectorySmoothing(const camera::CCameraModel& cam, bool live);

  /** One processed frame: the filter's pose and the low-innovation and rescued inliers of its
   * update, as undistorted normalised points, with how well the filter knows the depth of each
   * (`slam`: the filter after the frame), and the shadow filter's held-back matches it releases
   * (their frames counted from the first frame given, as here). */
  void addFrame(const system::TSystemFrame& fr, const slam::CMonoSlamIMM& slam, const core::TStampedPose& pose,
                const std::vector<system::CHeldBackMatches::TMatch>& heldBack);

  /** Stops the smoother, writes `path` (TUM, every frame), fills the summary's smoothed ATE (when
   * `gt` is given), lag and CPU share, and logs one line. */
  void finish(const std::string& path, const std::optional<core::TTrajectory>& gt, TRunSummary& summary,
              mrpt::system::COutputLogger& log);

  /** The smoothed trajectory written by finish() (empty before). */
  const core::TTrajectory& trajectory() const { return m_result; }

  /** What the scenes draw: before finish(), the keyframes optimised so far at their smoothed poses
   * (the smoother's lag behind the filter); after it, trajectory(). */
  core::TTrajectory published() const;

 private:
  const camera::CCameraModel& m_cam;
  refine::CKeyframeSmoother m_smoother;
  core::TTrajectory m_result;
};
}  // namespace immslam::app::detail
