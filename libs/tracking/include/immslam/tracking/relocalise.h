/* imm-monoslam — relocalisation against the existing map when tracking is lost.
 *
 * The active search of MonoSLAM only looks where the filter predicts: after a blackout, a gap in the
 * frames or a motion no model predicted, the features are in the image but outside their search
 * regions, and the classic rule (10 searches, < 50 % found) deletes the whole map. This module finds
 * the map again in the spirit of Williams, Klein & Reid ("Real-time SLAM relocalisation", ICCV 2007;
 * here without their classifier): every map feature with a known depth is looked for at the corners of
 * the whole image by the ZNCC of its stored template, and the camera pose is the RANSAC PnP solution
 * of those 2D-3D correspondences (OpenCV's solvePnPRansac on undistorted normalized coordinates, so
 * any camera model of libs/camera works). The SLAM filter then re-expresses its camera-centred state
 * in the found pose (applyPoseCorrection in robocentric_prediction.h) and its active search resumes.
 * Pure function: no state, no I/O. */
#pragma once

#include <immslam/camera/CCameraModel.h>
#include <immslam/math/types.h>

#include <opencv2/core/mat.hpp>

#include <cstdint>
#include <vector>

namespace immslam::slam
{
/** A map point the relocaliser may use: its world position (depth known) and appearance. */
struct TRelocPoint
{
  std::int64_t id = -1;
  Vec3 p_W = Vec3::Zero();
  /** Its appearance: one or more templates (CV_32F, odd and square, the same size for every point),
   * e.g. the stored patch as first seen and as it should look from where the camera was last tracked
   * (CFeaturePatch::predictTemplate). A corner's score is the best over them. */
  std::vector<cv::Mat> templates;
};

struct TRelocaliseParams
{
  int fastThreshold = 20;     ///< FAST threshold of the corners looked at (grey levels)
  int maxCorners = 1500;      ///< strongest FAST corners kept (bounds the cost)
  double minNcc = 0.8;        ///< a template matches a corner with ZNCC >= this
  /** A match is dropped when another corner, more than 3 px away, scores within this margin of the
   * best (repeated texture: the match would be a guess). */
  double ambiguityMargin = 0.02;
  double reprojectionPx = 2.5;  ///< RANSAC inlier threshold (px, at the mean focal length)
  int minInliers = 8;           ///< fewer PnP inliers: no relocalisation
  int ransacIterations = 300;
  cv::Mat validMask;  ///< optional CV_8UC1 mask: corners only where non-zero (frontend::lensMask)
};

struct TRelocalisation
{
  bool ok = false;
  Vec3 r_CW = Vec3::Zero();      ///< the found pose T_C_W: p_C = R(q_CW) p_W + r_CW
  Vec4 q_CW = Vec4(1, 0, 0, 0);  ///< [qw qx qy qz]
  int nCorners = 0;              ///< corners looked at
  int nCorrespondences = 0;      ///< map points with an unambiguous match
  std::vector<std::int64_t> inlierIds;
  std::vector<Vec2> inlierUv;    ///< the inliers' matched pixels
  double medianDepth = 0;        ///< of the inliers in the found camera
};

/** Looks for `points` in `grey` and solves for the camera pose. Deterministic (OpenCV's RANSAC uses a
 * fixed seed). Cost: FAST over the image plus 121 multiply-adds per (point, corner) pair, about
 * 2-5 ms for 30 points at 320x240; run only while lost.
 * \throws std::runtime_error if grey is not a non-empty CV_8UC1 image. */
TRelocalisation relocalise(const cv::Mat& grey, const camera::CCameraModel& cam, const std::vector<TRelocPoint>& points,
                           const TRelocaliseParams& p);
}  // namespace immslam::slam
