/* imm-monoslam — relative pose error (RPE) over a fixed frame delta. */
#pragma once

#include <immslam/core/TTrajectory.h>
#include <immslam/eval/alignment.h>

#include <cstddef>
#include <vector>

namespace immslam::eval
{
/** Relative error between associated pairs k and k + delta. */
struct TRpePairError
{
  double tStart = 0;        ///< ground-truth timestamp of pair k (s)
  double tEnd = 0;          ///< ground-truth timestamp of pair k + delta (s)
  double translation = 0;   ///< |s dp_est - dp_gt| (relative translations in the first pose's frame)
  double rotationDeg = 0;   ///< angle of dR_gt^T dR_est, degrees
  /** Angle between dp_est and dp_gt, degrees: the direction of the relative translation, free of
   * any scale (monocular SLAM); NaN when either translation is shorter than TRpeResult::minMotion. */
  double directionDeg = 0;
  /** Local scale |s dp_est| / |dp_gt|: 1 where the estimate's scale over this motion is the
   * trajectory's overall one; its spread over a run is the scale drift of a monocular estimate.
   * NaN where directionDeg is (a ground-truth motion too short to measure). */
  double scaleRatio = 0;
};

/** Result of computeRpe(). */
struct TRpeResult
{
  int delta = 1;                 ///< step in associated pairs
  size_t nPairs = 0;             ///< number of relative motions compared
  double scale = 1;              ///< s applied to the estimate's relative translations
  double translationRmse = 0;    ///< RMS translation error (gt units)
  double translationMean = 0;    ///< mean translation error
  double translationMedian = 0;  ///< median translation error
  double translationMax = 0;     ///< largest translation error
  double rotationRmseDeg = 0;    ///< RMS rotation error (degrees)
  double rotationMeanDeg = 0;    ///< mean rotation error
  double rotationMedianDeg = 0;  ///< median rotation error
  double rotationMaxDeg = 0;     ///< largest rotation error
  double minMotion = 0;          ///< the shortest gt relative translation with a direction error
  size_t nDirections = 0;        ///< relative motions with a direction error
  double directionMedianDeg = 0; ///< median direction error (degrees; NaN if none)
  double directionRmseDeg = 0;   ///< RMS direction error
  /** Local scale ratios (TRpePairError::scaleRatio) of the motions with a direction: median, 10th and
   * 90th percentiles, and the RMS of their logarithm (0 without drift; ln 2 = 0.69 for a factor 2);
   * NaN if none. */
  double scaleRatioMedian = 0, scaleRatioP10 = 0, scaleRatioP90 = 0, scaleLogRms = 0;
  std::vector<TRpePairError> errors;  ///< one per compared relative motion, in time order
};

/** Relative pose error (Sturm et al., IROS 2012): poses are associated by timestamp, sorted by
 * ground-truth time, and the relative motion from pair k to pair k + delta is compared:
 * \f$ E_k = (Q_k^{-1} Q_{k+\delta})^{-1} (P_k^{-1} P_{k+\delta}) \f$ with the estimate's relative
 * translation multiplied by the scale s. A rigid alignment does not change relative motions, so
 * only s matters: from the Sim3 Umeyama alignment of the associated positions (a = Sim3) or 1
 * (SE3, None). The direction error of the relative translation (scale-free) is computed for the
 * motions whose ground-truth translation is at least 10 % of the median one (shorter ones are
 * dominated by ground-truth noise and have no direction to speak of), and so is the local scale
 * |s dp_est| / |dp_gt| of those motions (the scale drift of a monocular estimate: with a Sim3
 * alignment 1 means the run's overall scale).
 * \param delta step in associated pairs (>= 1): 1 = consecutive associated frames.
 * \throws std::invalid_argument if delta < 1; std::runtime_error if fewer than delta + 1 pairs. */
TRpeResult computeRpe(const core::TTrajectory& est, const core::TTrajectory& gt, int delta = 1,
                      EAlignment a = EAlignment::Sim3, double maxDt = 0.01);
}  // namespace immslam::eval
