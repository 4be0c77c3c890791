/* imm-monoslam — filter consistency: NEES, chi-square bands over Monte Carlo runs, pose errors. */
#pragma once

#include <immslam/math/types.h>

#include <cstddef>
#include <vector>

namespace immslam::eval
{
/** Normalized estimation error squared \f$ \epsilon = e^\top P^{-1} e \f$ (Bar-Shalom, Li and
 * Kirubarajan, "Estimation with Applications to Tracking and Navigation", sec. 5.4.2), computed
 * with a Cholesky factor of P (only P's lower triangle is read).
 * \return +infinity if P is not positive definite or a value is not finite.
 * \throws std::invalid_argument if the sizes do not match. */
double nees(const VecX& err, const MatX& P);

/** A two-sided acceptance interval for an average NEES. */
struct TChi2Band
{
  double lower = 0;          ///< lower bound of the average NEES
  double upper = 0;          ///< upper bound
  double confidence = 0.95;  ///< probability mass inside for a consistent filter
  int dof = 0;               ///< dimension of the error
  int nRuns = 0;             ///< Monte Carlo runs averaged

  /** lower <= x <= upper. */
  bool contains(double x) const { return x >= lower && x <= upper; }
};

/** Band for the N-run average NEES of a dof-dimensional error: N times that average is
 * chi-square with N dof degrees of freedom for a consistent filter, so (Bar-Shalom et al.,
 * eq. 5.4.2-7) the band is
 * \f$ [\chi^2_{N n}((1-c)/2) / N,\; \chi^2_{N n}((1+c)/2) / N] \f$ (math::chi2Quantile).
 * E.g. dof 6, 25 runs, c = 0.95: [4.719, 7.432].
 * \throws std::invalid_argument unless dof >= 1, nRuns >= 1 and 0 < confidence < 1. */
TChi2Band averageNeesBand(int dof, int nRuns, double confidence = 0.95);

/** Collects NEES values of Monte Carlo runs per time step and tests them against the
 * average-NEES band: add each run's NEES at each step, then read the per-step averages and the
 * fraction of steps whose average lies inside the band (about the confidence for a consistent
 * filter). Steps may receive different numbers of runs; each step uses its own band. */
class CNeesAccumulator
{
 public:
  /** \param dof dimension of the errors (>= 1). */
  explicit CNeesAccumulator(int dof);

  /** Adds one run's NEES value at a time step (steps are created as needed). */
  void add(size_t step, double neesValue);
  /** Adds nees(err, P) at a time step (err must have dof entries). */
  void add(size_t step, const VecX& err, const MatX& P);

  int dof() const { return m_dof; }
  /** Number of steps (highest step added + 1). */
  size_t numSteps() const { return m_sum.size(); }
  /** Number of runs added at a step (0 if none). */
  size_t runsAt(size_t step) const;
  /** Average NEES at a step (NaN if no run was added there). */
  double averageAt(size_t step) const;
  /** averageAt() of every step. */
  std::vector<double> averages() const;
  /** Mean of all added NEES values (ideally dof); NaN if none. */
  double overallAverage() const;
  /** Fraction of the steps with at least one run whose average lies in
   * averageNeesBand(dof, runsAt(step), confidence); NaN if no step has a run. */
  double fractionInsideBand(double confidence = 0.95) const;

 private:
  int m_dof;
  std::vector<double> m_sum;
  std::vector<size_t> m_count;
};

/** Pose error [dp; dtheta] (6) of an estimate (p_est, q_est) against the truth (p_true, q_true),
 * quaternions [qw qx qy qz]:
 * - dp = p_est - p_true, in W;
 * - dtheta = Log(q_true^-1 q_est), the rotation vector of the error in the camera frame C
 *   (a right perturbation: R_est = R_true Exp([dtheta]x)); for small errors
 *   dtheta ~ 2 vec(q_true^-1 q_est). The angle is in [0, pi] (sign of q is irrelevant).
 * Its covariance is poseCovariance6() of the filter's [r; q] covariance. */
Vec6 poseError6(const Vec3& p_est, const Vec4& q_est, const Vec3& p_true, const Vec4& q_true);

/** Covariance of poseError6() from a filter's 7x7 covariance over [r; q] (state order of
 * doc/conventions.md): \f$ G P G^\top \f$, \f$ G = \mathrm{diag}(I_3, J) \f$ with
 * \f$ J = \partial\,\mathrm{Log}(\hat q^{-1} q)/\partial q |_{q=\hat q} = 2 [0\; I_3]\, L(\hat q^{*}) \f$
 * (L(a) the matrix of a (x) . ), which removes the quaternion's norm direction.
 * \param q_est the estimate (unit quaternion) the filter's covariance is centred on.
 * \param P_rq 7x7 covariance of [r; q].
 * \param J_theta_q optional output: J (3x4).
 * \throws std::invalid_argument if P_rq is not 7x7. */
Mat6 poseCovariance6(const Vec4& q_est, const MatX& P_rq, Mat34* J_theta_q = nullptr);

/** nees(poseError6(...), poseCovariance6(q_est, P_rq)): the 6-dof pose NEES of a filter. */
double poseNees(const Vec3& p_est, const Vec4& q_est, const Vec3& p_true, const Vec4& q_true,
                const MatX& P_rq);
}  // namespace immslam::eval
