/* imm-monoslam — statistical tests of incidence and identity relations between uncertain entities
 * (shadow-filter paper, eqs. (13)-(14), after Heuel 2004, sec. 3.5). */
#pragma once

#include <immslam/geometry/TUncertainLine3.h>
#include <immslam/geometry/TUncertainPlane3.h>
#include <immslam/geometry/TUncertainPoint3.h>
#include <immslam/geometry/geometry_types.h>

#include <limits>

namespace immslam::geometry
{
/** Outcome of testing \f$ H_0: \mathbf d = \mathbf 0 \f$ (eq. (13)) with eq. (14). */
struct THypothesisTest
{
  /** Test statistic \f$ T = \mathbf d^\top \Sigma_{dd}^{+(r)} \mathbf d \f$ (rank-r pseudo-inverse,
   * see testRelation()); NaN when !valid. */
  double T = std::numeric_limits<double>::quiet_NaN();
  /** Degrees of freedom r of the relation. */
  int dof = 0;
  /** Critical value \f$ \varepsilon_H = \chi^2_{1-\alpha;\,r} \f$ (math::chi2Quantile, exact). */
  double threshold = std::numeric_limits<double>::quiet_NaN();
  /** \f$ T < \varepsilon_H \f$: H0 (the relation holds) is not rejected at significance alpha.
   * False when !valid. */
  bool accepted = false;
  /** False when the test could not be evaluated: non-finite d or \f$ \Sigma_{dd} \f$, or fewer than r
   * positive eigenvalues (the inputs carry no uncertainty in the directions the relation needs, or the
   * configuration is degenerate, e.g. parallel rays). Then neither accepted nor rejected. */
  bool valid = false;

  /** H0 rejected by a valid test. */
  bool rejected() const { return valid && !accepted; }
};

/** The r eigenvectors of the symmetric matrix cov with the largest eigenvalues (n x r, columns in
 * decreasing eigenvalue order), and optionally those eigenvalues. Projecting a distance vector on them,
 * \f$ U_r^\top \mathbf d \f$, keeps r independent combinations of its rows. */
MatX dominantEigenvectors(const MatX& cov, int r, VecX* eigenvalues = nullptr);

/** A significance level with the chi-square critical values \f$ \chi^2_{1-\alpha;\,r} \f$ of r = 1-4
 * degrees of freedom, computed once. math::chi2Quantile is a bisection of the incomplete gamma
 * function (about 45 evaluations of it); tests run for every feature in every frame (the shadow
 * filter's) take their thresholds from here: the same numbers, bitwise. */
struct TSignificance
{
  double alpha = 0;
  double chi2[5] = {0, 0, 0, 0, 0};  ///< chi2[r] for r = 1-4 (chi2[0] unused)

  /** \throws std::invalid_argument for alpha outside (0, 1). */
  static TSignificance At(double alpha);
  /** \f$ \chi^2_{1-\alpha;\,r} \f$: from the table for r = 1-4, computed otherwise. */
  double threshold(int dof) const;
};

/** Generic test of eq. (14) for a distance vector d (n rows) of a relation with r <= n degrees of
 * freedom.
 *
 * When n > r, \f$ \Sigma_{dd} \f$ is singular to first order at the true values, and evaluated at the
 * observed (noisy) values it is merely ill-conditioned: its n - r smallest eigenvalues are
 * second-order noise, and inverting them would inflate T arbitrarily. We therefore use the rank-r
 * pseudo-inverse from the eigen-decomposition, keeping the r largest eigenvalues:
 * \f$ T = \sum_{i \le r} (\mathbf u_i^\top \mathbf d)^2 / \lambda_i \f$. Unlike Heuel's selection of r
 * rows of d (which depends on the entities' coordinates and has to pick rows case by case), this is
 * independent of the coordinate frame, needs no case analysis, and for a d lying in the range of
 * \f$ \Sigma_{dd} \f$ it equals the Mahalanobis distance in that range (invariant to any invertible
 * recombination of the rows of d). Under H0, T is \f$ \chi^2_r \f$ to first order.
 * \param alpha significance level, 0 < alpha < 1 (type-I error rate).
 * \throws std::invalid_argument for inconsistent sizes, r outside [1, n] or alpha outside (0, 1). */
THypothesisTest testRelation(const VecX& d, const MatX& cov_dd, int dof, double alpha);
/** testRelation() at a level whose critical values are computed already. */
THypothesisTest testRelation(const VecX& d, const MatX& cov_dd, int dof, const TSignificance& level);

/** \name Incidence and identity tests
 * Each spherically normalizes its inputs first (Heuel's practice; lines also get the covariance
 * projection of TUncertainLine3::normalized()), builds the bilinear distance d = U(x) y of eq. (13),
 * propagates \f$ \Sigma_{dd} \f$ with eq. (11)/(12) and calls testRelation(). The optional
 * cross-covariance is \f$ E[\delta x \delta y^\top] \f$ of the two arguments in their given order and
 * scale (it is normalized along with them).
 * @{ */

/** Point on plane: \f$ d = \mathbf A^\top \mathbf X \f$, r = 1. */
THypothesisTest testPointOnPlane(const TUncertainPoint3& X, const TUncertainPlane3& A, double alpha,
                                 const Mat4* cov_XA = nullptr);

/** Point on line: \f$ \mathbf d = O(\mathbf L)\mathbf X \f$ (the plane X ^ L vanishes, eq. (8)),
 * 4 rows, r = 2. */
THypothesisTest testPointOnLine(const TUncertainPoint3& X, const TUncertainLine3& L, double alpha,
                                const Mat46* cov_XL = nullptr);

/** Line in plane: \f$ \mathbf d = \bar O(\mathbf L)\mathbf A \f$ (the point L meet A vanishes),
 * 4 rows, r = 2. */
THypothesisTest testLineOnPlane(const TUncertainLine3& L, const TUncertainPlane3& A, double alpha,
                                const Mat64* cov_LA = nullptr);

/** Two lines coplanar (intersecting or parallel): \f$ d = \mathbf L^\top D \mathbf M \f$, r = 1. */
THypothesisTest testLinesCoplanar(const TUncertainLine3& L, const TUncertainLine3& M, double alpha,
                                  const Mat6* cov_LM = nullptr);

/** Identical points: \f$ \mathbf d = \Pi(\mathbf X)\mathbf Y \f$ (the join vanishes), 6 rows, r = 3. */
THypothesisTest testIdenticalPoints(const TUncertainPoint3& X, const TUncertainPoint3& Y, double alpha,
                                    const Mat4* cov_XY = nullptr);

/** Identical planes: \f$ \mathbf d = \bar\Pi(\mathbf A)\mathbf B \f$, 6 rows, r = 3. */
THypothesisTest testIdenticalPlanes(const TUncertainPlane3& A, const TUncertainPlane3& B, double alpha,
                                    const Mat4* cov_AB = nullptr);

/** Identical lines: \f$ \mathbf d = \mathrm{vec}(O(\mathbf L)\,\bar O(\mathbf M)) \f$ (every point of M,
 * \f$ \bar O(\mathbf M)\mathbf A \f$, joined with L gives no plane), 16 rows, r = 4. */
THypothesisTest testIdenticalLines(const TUncertainLine3& L, const TUncertainLine3& M, double alpha,
                                   const Mat6* cov_LM = nullptr);
/** @} */

/** The distance vector of testIdenticalLines(), vec(O(L) OBar(M)) (column-major, 16 rows), with
 * its Jacobians (16x6 each). */
VecX identicalLinesDistance(const Vec6& L, const Vec6& M, MatX* J_d_L = nullptr, MatX* J_d_M = nullptr);
}  // namespace immslam::geometry
