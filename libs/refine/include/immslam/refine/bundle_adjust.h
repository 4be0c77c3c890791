/* imm-monoslam — bundle adjustment of a TBundleProblem on Ceres: every pose and point refined to
 * minimise a robust (Huber) reprojection cost, with the gauge held by chosen poses. The offline
 * refinement of a whole run ([output] refine_trajectory, slam-eval reprojection --refine) and each
 * window of the online CKeyframeSmoother run this same function. */
#pragma once

#include <immslam/refine/bundle_problem.h>

#include <cstddef>
#include <vector>

namespace immslam::refine
{
/** Bundle adjustment options. */
struct TBundleOptions
{
  double huberPx = 2;       ///< Huber threshold of the robust cost (pixels)
  int maxIterations = 100;  ///< Levenberg-Marquardt iterations
  /** Poses held fixed (the gauge). Empty: the first pose of each connected component
   * (firstPoseOfEachComponent()). Otherwise these, plus the first pose of every component that
   * holds none of them. Holding two poses of a component fixes its scale as well. */
  std::vector<std::size_t> heldPoses;
  /** Every point held fixed: a motion-only adjustment, each pose refined against the points on its
   * own; no pose is then held beyond heldPoses (the points hold the gauge). */
  bool holdPoints = false;
  /** Scale gauge: the distance between the centres of pose scalePoses[0] (held) and scalePoses[1]
   * (otherwise free) stays as given, by a stiff residual. Empty: none. */
  std::vector<std::size_t> scalePoses;
  /** Outlier pass: once the adjustment has converged, the measurements whose reprojection error
   * exceeds this many times the median error (and outlierMinPx) are removed and the problem solved
   * again (outlierIterations). For Gaussian image noise the median error is
   * 1.18 sigma, so 3 times it is 3.5 sigma (0.2 % of good measurements); a mismatch, or a track that
   * slides along an edge (a T-junction, an occluding contour: no fixed point), stays far outside
   * once the rest is fitted, where the Huber cost alone still lets it pull. 0: no pass. */
  double outlierFactor = 3;
  double outlierMinPx = 0.5;   ///< the pass never removes a measurement within this error (pixels)
  /** Iterations of the second solve (at most maxIterations): the first solve's minimum is a close
   * start. A window of the online smoother takes 10 (it runs often, and 5 gave the same poses). */
  int outlierIterations = 100;
};

/** What a bundle adjustment did. */
struct TBundleResult
{
  int iterations = 0;
  double initialCost = 0, finalCost = 0;  ///< robust cost per measurement (px^2)
  bool converged = false;                 ///< the solver met a convergence tolerance
  std::size_t unused = 0;                 ///< measurements left out: their point starts behind the camera
  std::size_t components = 0;             ///< unrelated blocks of poses and points (one per map of the run)
  std::size_t outliers = 0;               ///< measurements the outlier pass removed (TBundleOptions::outlierFactor)
};

/** Levenberg-Marquardt bundle adjustment (Triggs et al., "Bundle Adjustment — A Modern Synthesis",
 * 2000) of all poses and points on Ceres (Schur complement on the points), one residual block per
 * measurement: reprojectionResidual()'s r = (fx (x - q_x/q_z), fy (y - q_y/q_z)), q = R_CW X + t_CW,
 * with a Huber loss, cost per measurement \f$\rho(|r|^2)\f$, \f$\rho(s) = s\f$ for
 * \f$s \le k^2\f$ and \f$2k\sqrt{s} - k^2\f$ beyond (k = huberPx). Rotations R_CW are unit
 * quaternions on their manifold (updates exp(dtheta) q), translations and points Euclidean.
 * A measurement whose point starts behind its camera is left out (TBundleResult::unused); a step
 * that would put a used point behind its camera is rejected. The gauge: TBundleOptions::heldPoses.
 * The scale of a component held by one pose is left to the damping (the cost does not change along
 * it). Pose timestamps are kept; poses that measure nothing are not changed. Single-threaded and
 * deterministic. */
TBundleResult bundleAdjust(TBundleProblem& problem, const TBundleOptions& opts = {});

/** For a program's main (a library never calls it): Ceres's log messages off. A window without
 * parallax (a camera at rest or rotating) leaves points' depths unconstrained; Levenberg-Marquardt then
 * logs a warning ("Linear solver failure ... dense Cholesky factorization") for each step it rejects
 * and an error when it stops after too many. The solve keeps its best step (the cost never rises) and
 * its outcome is in TBundleResult (the smoother counts the windows that did not converge, and the run
 * reports them). GLOG_minloglevel, when set in the environment, decides instead (0: everything). */
void quietSolverLog();

}  // namespace immslam::refine
