/* imm-monoslam — what one frame of the SLAM tracker did (CSlamTracker): per-feature search records
 * and the frame's figures (frame_stats.csv, searches.csv, overlays). Plain data. */
#pragma once

#include <immslam/math/types.h>

#include <cstdint>
#include <vector>

namespace immslam::slam
{
/** What happened to one feature in one frame (for overlays and statistics). */
struct TSearchRecord
{
  std::int64_t id = -1;
  Vec2 h = Vec2::Zero();      ///< IMM-fused predicted pixel (eq. 13)
  Mat2 S = Mat2::Identity();  ///< IMM-fused innovation covariance (eq. 14)
  bool found = false;         ///< the active search found a match
  Vec2 z = Vec2::Zero();      ///< measured pixel (when found)
  double score = -1;          ///< best ZNCC inside the ellipse (also when below the threshold)
  enum class EStatus
  {
    NotFound,
    LowInnovationInlier,
    RescuedInlier,
    Rejected
  } status = EStatus::NotFound;
};

/** Per-frame figures (frame_stats.csv). */
struct TFrameReport
{
  double timestamp = 0;
  std::int64_t frame = 0;
  int nMap = 0;              ///< features in the SLAM state after the frame
  int nPredicted = 0;        ///< features predicted in the image and searched
  int nFound = 0;            ///< searches that found a match
  int nMatched = 0;          ///< measurements used in the update
  int nRejected = 0;         ///< found matches rejected as outliers
  int nLowInnovation = 0, nRescued = 0, nHypotheses = 0;
  double meanSearchAreaPx2 = 0;  ///< mean of pi * 5.991 * sqrt(det S_i) over searched features
  double sigmaPixel = 0;         ///< measurement noise std used in this frame (px)
  /** Angular acceleration noise of the loosest general model for the next frame (px). */
  double motionNoiseAngularPx = 0;
  double shakePx = 0;  ///< the angular shake the next prediction uses (px per frame; CImmSlamFilter::shakePx)
  int nDepthKnown = 0;       ///< rho - 1.96 sigma_rho > 0, or XYZ
  int nAdded = 0, nDeleted = 0, nConverted = 0;
  double dtFrames = 1;       ///< elapsed time in nominal frame periods
  bool expandedSearch = false;  ///< the expanded search ran (most matches outside their ellipses)
  double timeMs = 0;         ///< wall time of processFrame
  // Stage timings (ms)
  double tPredictMs = 0, tSearchMs = 0, tRansacMs = 0, tUpdateMs = 0, tMapMs = 0;
  int nDormantModes = 0;     ///< IMM modes not updated this frame (TIMMBankOptions::dormant_below)
  int nLazyModes = 0;        ///< of them, modes whose covariance was not predicted either (lazy_prediction)
  int lostFrames = 0;        ///< lost frames in a row before this one (TOptions::relocalise)
  bool relocalised = false;  ///< this frame's pose was found by relocalisation
  int nRelocMatches = 0;     ///< map points matched (unambiguously) by the relocalisation attempt
  int nRelocInliers = 0;     ///< PnP inliers of the relocalisation attempt (0: none tried or failed early)
  double tRelocMs = 0;       ///< time of the relocalisation attempt (ms)
  std::vector<TSearchRecord> searches;
  /** The camera's motion since frame relFrom (CSlamTracker::setRelativePoseLag): the relative pose
   * T_{C_j C_k} (p_Cj = R(relQ) p_Ck + relT, the map's units) from the pose clone of frame j, with the
   * filter's covariance relCov of [dt; dtheta] (t = t_hat + dt, R = R_hat Exp(dtheta)); relFrom < 0: none. */
  std::int64_t relFrom = -1;
  double relFromTimestamp = 0;
  Vec3 relT = Vec3::Zero();
  Vec4 relQ = Vec4(1, 0, 0, 0);
  Mat6 relCov = Mat6::Zero();
};
}  // namespace immslam::slam
