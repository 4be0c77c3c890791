/* imm-monoslam — absolute trajectory error (ATE) after Sim(3)/SE(3) alignment. */
#pragma once

#include <immslam/core/TTrajectory.h>
#include <immslam/eval/alignment.h>

#include <cstddef>
#include <utility>
#include <vector>

namespace immslam::eval
{
/** Error of one associated (estimate, ground truth) pose pair after alignment. */
struct TAtePairError
{
  size_t iEst = 0;           ///< index into the estimate
  size_t iGt = 0;            ///< index into the ground truth
  double tEst = 0;           ///< estimate timestamp (s)
  double tGt = 0;            ///< ground-truth timestamp (s)
  double position = 0;       ///< |p_gt - (s R p_est + t)|, in ground-truth units
  double rotationDeg = 0;    ///< angle of q_gt^-1 (q_R q_est), degrees in [0, 180]
};

/** Result of computeAte(): statistics of the position errors after alignment. */
struct TAteResult
{
  EAlignment alignment = EAlignment::Sim3;  ///< alignment used
  size_t nPairs = 0;        ///< associated pose pairs
  double rmse = 0;          ///< RMS position error (gt units)
  double mean = 0;          ///< mean position error
  double median = 0;        ///< median position error
  double max = 0;           ///< largest position error
  double scale = 1;         ///< s of the alignment (1 unless Sim3)
  Mat3 R = Mat3::Identity();  ///< rotation of the alignment
  Vec3 t = Vec3::Zero();    ///< translation of the alignment
  int alignmentRank = 3;    ///< rank of the cross-covariance (alignUmeyama); < 2 means degenerate
  double pathLength = 0;    ///< sum of |gt_{i+1} - gt_i| over the associated gt poses in time order
  double extent = 0;        ///< diagonal of the axis-aligned bounding box of the associated gt positions
  double rmseOverPath = 0;  ///< rmse / pathLength (+inf if pathLength = 0 < rmse, 0 if both are 0)
  double rmseOverExtent = 0;  ///< rmse / extent (same conventions)
  double rotationRmseDeg = 0;  ///< RMS of the per-pair rotation errors after alignment, degrees
  std::vector<TAtePairError> errors;  ///< per pair, in estimate time order

  /** The alignment as a TSim3 {scale, R, t}. */
  TSim3 sim3() const { return TSim3{scale, R, t}; }
};

/** Applies x -> s R x + t to every position and R to every orientation (q <- q_R q, normalized);
 * timestamps unchanged. */
core::TTrajectory applySim3(const TSim3& S, const core::TTrajectory& traj);

/** Alignment of est onto gt over given pairs (est index, gt index): alignUmeyama on the
 * positions with scale (Sim3), without (SE3), or the identity (None).
 * \param rank optional output, as in alignUmeyama (3 for None). */
TSim3 alignTrajectories(const core::TTrajectory& est, const core::TTrajectory& gt,
                        const std::vector<std::pair<size_t, size_t>>& pairs, EAlignment a,
                        int* rank = nullptr);

/** Absolute trajectory error (Sturm et al., IROS 2012): associates est with gt by timestamp
 * (associateByTimestamp, maxDt), aligns est onto gt (EAlignment) with Umeyama's method, and
 * measures the position error of every pair (and the rotation error after the same rotation).
 * \throws std::runtime_error if no pair is found within maxDt. */
TAteResult computeAte(const core::TTrajectory& est, const core::TTrajectory& gt,
                      EAlignment a = EAlignment::Sim3, double maxDt = 0.01);

/** The per-pair errors of computeAte() (for plots of error against time). */
std::vector<TAtePairError> ateOverTime(const core::TTrajectory& est, const core::TTrajectory& gt,
                                       EAlignment a = EAlignment::Sim3, double maxDt = 0.01);
}  // namespace immslam::eval
