/* imm-monoslam — the bundle problem: poses, points and the image measurements that join them (the
 * matches of the app's searches.csv, or those a CKeyframeSmoother collected), every feature
 * triangulated from the given poses, and its reprojection error per feature.
 *
 * Use: is a "ground truth" consistent with the images? is an estimate? how well do the images
 * determine the trajectory at all? bundleAdjust() (bundle_adjust.h) refines such a problem. */
#pragma once

#include <immslam/core/TTrajectory.h>
#include <immslam/eval/search_nis.h>
#include <immslam/math/types.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace immslam::camera
{
class CCameraModel;
}

namespace immslam::refine
{
/** One measurement: feature `point` seen from pose `pose` at the undistorted normalized image
 * point xn = (x/z, y/z) of the camera frame. */
struct TBundleObservation
{
  std::size_t pose = 0;
  std::size_t point = 0;
  Vec2 xn = Vec2::Zero();
};

/** Poses, points and measurements of a bundle adjustment. Poses are T_W_C (as in TUM files);
 * residuals are in undistorted pixels: (fx (x - x^), fy (y - y^)) with the camera's focal lengths
 * (exact pixels for a pinhole camera, the undistorted image for the others). */
struct TBundleProblem
{
  core::TTrajectory poses;                      ///< camera poses T_W_C, in time order
  std::vector<std::int64_t> featureIds;   ///< id of each point (searches.csv feature_id)
  std::vector<Vec3> points;               ///< feature positions in W
  std::vector<TBundleObservation> obs;    ///< measurements, grouped by point
  double fx = 1, fy = 1;                  ///< pixel scale of the residuals
};

/** The residual of one measurement and its Jacobians, for a pose given as camera-from-world
 * (R_CW, t_CW) perturbed on the left: R_CW <- exp([dtheta]x) R_CW, t_CW <- t_CW + dt.
 * r = (fx (xn_x - q_x/q_z), fy (xn_y - q_y/q_z)) with q = R_CW X + t_CW.
 * \param J_pose d r / d(dtheta, dt), 2x6; \param J_point d r / d X, 2x3 (either may be null).
 * \return false if the point is not in front of the camera (q_z <= 0; r is then undefined). */
bool reprojectionResidual(const Mat3& R_CW, const Vec3& t_CW, const Vec3& X_W, const Vec2& xn, double fx,
                          double fy, Vec2& r, Eigen::Matrix<double, 2, 6>* J_pose = nullptr,
                          Mat23* J_point = nullptr);

/** Builds the problem from the matches used in the SLAM updates (status inlier or rescued) of a
 * searches.csv, joined to `poses` by timestamp (|dt| <= maxDt), keeping the features seen from at
 * least `minViews` poses that each measure at least `minPerPose` of those features (a pose with
 * fewer is not determined by them: it is left out with its measurements); the points are
 * triangulated (triangulateAll()). Poses are kept in time order.
 * \throws std::invalid_argument if minViews < 2, minPerPose < 1 or maxDt < 0;
 * \throws std::runtime_error if no feature has minViews joined measurements (the message says how
 *         many rows were used and joined: a wrong trajectory file shows as 0 joined). */
TBundleProblem makeBundleProblem(const std::vector<eval::TSearchRow>& rows, const core::TTrajectory& poses,
                                 const camera::CCameraModel& cam, double maxDt, int minViews,
                                 int minPerPose = 6);

/** Reprojection error statistics of a problem (pixels). */
struct TReprojectionStats
{
  std::size_t nFeatures = 0, nObservations = 0, nPoses = 0;
  double rmsPx = 0;              ///< RMS over all measurements
  double medianFeatureRmsPx = 0; ///< median over features of each feature's RMS
  double p90FeatureRmsPx = 0;    ///< 90th percentile of the same
  std::size_t featuresAbove = 0; ///< features whose RMS exceeds `thresholdPx`
  double thresholdPx = 2;
  std::vector<double> featureRmsPx;  ///< per point, in problem order

  /** Multi-line report. */
  std::string summary() const;
};

/** Re-triangulates every point from the fixed poses (linear DLT on the normalized points, then
 * Gauss-Newton on the reprojection error) and returns the statistics: the error of the best point
 * for each feature given the trajectory. Points the poses cannot locate (all centres equal, e.g.
 * a pure rotation) end far along their ray; their error is that of the bearing alone. */
TReprojectionStats triangulateAll(TBundleProblem& problem, double thresholdPx = 2);

/** Statistics of the problem as it is (no re-triangulation). */
TReprojectionStats reprojectionStats(const TBundleProblem& problem, double thresholdPx = 2);

/** The first pose (lowest index) of each connected component of the problem, poses being connected
 * by the points they measure (measurements with used[i] == 0 ignored; empty `used`: all): one
 * component per map of a run that started a new map (kidnapped, map given up), each with its own
 * gauge. A pose measuring nothing is a component of its own. */
std::vector<std::size_t> firstPoseOfEachComponent(const TBundleProblem& p, const std::vector<char>& used = {});

/** The component of every pose (the index of its first pose, as firstPoseOfEachComponent()). */
std::vector<std::size_t> componentOfEachPose(const TBundleProblem& p, const std::vector<char>& used = {});

}  // namespace immslam::refine
