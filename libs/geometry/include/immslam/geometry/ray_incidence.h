/* imm-monoslam — do three uncertain viewing rays meet in one point? The geometric core of the shadow
 * filter's static/dynamic classifier (shadow-filter paper, sec. III-A). */
#pragma once

#include <immslam/geometry/TUncertainLine3.h>
#include <immslam/geometry/TUncertainPoint3.h>
#include <immslam/geometry/geometry_types.h>
#include <immslam/geometry/hypothesis_tests.h>

namespace immslam::geometry
{
/** The viewing ray from the camera centre c along the world direction d (e.g. \f$ R_{WC} K^{-1}
 * (u, v, 1)^\top \f$), as the join of the centre with the point at infinity of d (eq. (6)):
 * \f$ \mathbf L = (\mathbf c, 1) \wedge (\mathbf d, 0) = (\mathbf d,\; \mathbf c \times \mathbf d) \f$.
 * The point at infinity is the limit of "a far point on the ray" and, unlike a finite far point
 * \f$ \mathbf c + s\mathbf d \f$, is not correlated with the centre through c; it is
 * correlated with it only when the orientation uncertainty is correlated with the position.
 * \param cov_centre covariance of c (3x3, e.g. the SLAM filter's camera position block).
 * \param cov_direction covariance of d (3x3; d's scale is irrelevant, so its component along d does
 *        not matter). For pixel noise sigma (px) and focal f, \f$ R\,\mathrm{diag}(\sigma^2/f^2,
 *        \sigma^2/f^2, 0)R^\top \f$ for \f$ d = R\,((u-c_x)/f, (v-c_y)/f, 1)^\top \f$.
 * \param cov_centre_direction optional \f$ E[\delta c\, \delta d^\top] \f$. */
TUncertainLine3 viewingRay(const Vec3& centre, const Mat3& cov_centre, const Vec3& direction,
                           const Mat3& cov_direction, const Mat3* cov_centre_direction = nullptr);

/** The point of the line L nearest to the line M (the foot on L of their common perpendicular); for
 * intersecting lines their intersection point. Construction (all bilinear, eqs. (7)-(9)):
 * the point at infinity \f$ \mathbf N = (\mathbf M_h \times \mathbf L_h, 0) \f$ of the common normal,
 * the plane \f$ \mathbf A = \mathbf N \wedge \mathbf M = O(\mathbf M)\mathbf N \f$ through M
 * containing that normal, and \f$ \mathbf X = \mathbf L \cap \mathbf A = \bar O(\mathbf L)\mathbf A \f$.
 * Zero (undefined) for parallel lines.
 * \param J_X_L, J_X_M optional 4x6 Jacobians (chain rule through N and A). */
Vec4 nearestPointOnLine(const Vec6& L, const Vec6& M, Mat46* J_X_L = nullptr, Mat46* J_X_M = nullptr);

/** The distance vector of the concurrency test, before reduction (5 rows):
 * \f$ \mathbf d = (\mathbf L_i^\top D \mathbf L_j,\; (O(\mathbf L_k)\mathbf X_{ij})^\top)^\top \f$ with
 * \f$ \mathbf X_{ij} = \bar O(\mathbf L_j)\, O(\mathbf L_i)\, (\mathbf v, 0) \f$: the point where L_j
 * cuts the plane through L_i parallel to the auxiliary direction v. With
 * \f$ \mathbf v = \mathbf L_{i,h} \times \mathbf L_{j,h} \f$ this is nearestPointOnLine(L_j, L_i).
 * v is an input held constant (its Jacobian is not taken): when the rays meet, every plane through L_i
 * other than the one containing L_j cuts L_j at their common point, so d does not depend on v to
 * first order under H0; holding it fixed keeps d linear in each ray (trilinear, like the trifocal
 * constraints), whereas differentiating \f$ \mathbf L_{i,h} \times \mathbf L_{j,h} \f$ makes d quadratic
 * in L_i and L_j, and that nonlinearity made the test over-cautious at small parallax.
 * Inputs as given (no normalization). \param J_d_Li, J_d_Lj, J_d_Lk optional 5x6 Jacobians. */
Eigen::Matrix<double, 5, 1> concurrencyDistance(const Vec6& Li, const Vec6& Lj, const Vec6& Lk,
                                                const Vec3& v,
                                                Eigen::Matrix<double, 5, 6>* J_d_Li = nullptr,
                                                Eigen::Matrix<double, 5, 6>* J_d_Lj = nullptr,
                                                Eigen::Matrix<double, 5, 6>* J_d_Lk = nullptr);

/** Result of threeRaysMeet(). */
struct TRayIncidenceTest
{
  /** The joint test that the three rays are concurrent, r = 3 (see threeRaysMeet()). */
  THypothesisTest test;
  /** Its 1-dof part alone: rays pair[0] and pair[1] are coplanar (diagnostic). */
  THypothesisTest coplanar;
  /** Its 2-dof part alone: the intersection point lies on ray `third` (diagnostic). */
  THypothesisTest onThirdRay;
  /** The point where rays pair[0] and pair[1] (nearly) meet: the point of ray pair[1] nearest to ray
   * pair[0], spherically normalized, with its covariance (first order, from the rays' joint
   * covariance). A triangulation of the feature from two views as a by-product. */
  TUncertainPoint3 intersection;
  int pair[2] = {0, 1};  ///< indices (0-based) of the two rays intersected
  int third = 2;         ///< index of the ray tested to pass through the intersection
};

/** Tests H0: the three uncertain rays (lines) meet in one point, at significance alpha.
 *
 * Formulation. Three lines are concurrent iff two of them, L_i and L_j, are coplanar (1 condition)
 * and their intersection point \f$ \mathbf X_{ij} \f$ lies on the third, L_k (2 conditions): r = 3, as
 * many as the measurements leave (3 views x 2 image coordinates - 3 coordinates of a static point).
 * - Not the three pairwise coplanarity tests: three pairwise coplanar lines may lie in one plane
 *   without meeting in a point (e.g. a feature moving inside the epipolar plane of three collinear
 *   camera centres), which those tests cannot see.
 * - Not "the plane through ray i and the camera centre of ray j, met with ray j": when the rays
 *   meet, that plane contains ray j and the meet vanishes identically. Instead \f$ \mathbf X_{ij} \f$ is
 *   where L_j cuts the plane through L_i parallel to the common normal
 *   \f$ \mathbf v = \mathbf L_{i,h} \times \mathbf L_{j,h} \f$ (the foot of the common perpendicular,
 *   nearestPointOnLine()), a transversal cut; v is evaluated once and held fixed (see
 *   concurrencyDistance() for why that is exact to first order and better behaved).
 *
 * The distance vector is concurrencyDistance(): \f$ d_1 = \mathbf L_i^\top D \mathbf L_j \f$ (1 row) and
 * \f$ \mathbf d_2 = O(\mathbf L_k)\mathbf X_{ij} \f$ (4 rows of rank 2). The Jacobian of d w.r.t. all
 * three rays (5x18) is built by the chain rule, so the reuse of L_i and L_j in both parts and inside
 * \f$ \mathbf X_{ij} \f$ is accounted for, as are cross-covariances between rays when given. \f$ \mathbf d_2 \f$ is reduced to its 2 dominant combinations \f$ U_2^\top \mathbf d_2 \f$
 * (dominantEigenvectors() of its own covariance, i.e. the rank-2 pseudo-inverse of testRelation())
 * before stacking with \f$ d_1 \f$, so the 3x3 covariance of the reduced vector is regular and the
 * test does not depend on the relative scale of the two parts. Rays are spherically normalized
 * first (TUncertainLine3::normalized()). The pair (i, j) is the one with the widest angle between
 * directions, for the best-conditioned intersection; the hypothesis is symmetric in the rays.
 *
 * Measured (geometry_unittest, 10 000 configurations with centres 0.05-0.5 apart, point 1-5 away,
 * 1 px noise at f = 200 px): 4.8 % rejections at alpha = 5 % under H0; the test is conservative
 * (2-4 %) when the widest parallax between rays is below ~0.04 rad (8 px), where first-order
 * propagation of a two-view triangulation is no longer accurate. A point moving 15 px across the
 * epipolar plane between views is rejected 99.9 % of the time. Motions that a static point explains
 * (e.g. along the epipolar direction at small parallax) are undetectable by any three-view test.
 * Degenerate geometry (parallel rays) or rays without any uncertainty give test.valid = false.
 * \param ray1, ray2, ray3 the viewing rays (e.g. from viewingRay()) with their covariances.
 * \param alpha significance level (the rate at which static features are called dynamic).
 * \param cov_rays optional 18x18 joint covariance of (ray1, ray2, ray3) in their given scale; when
 *        given, its diagonal blocks replace the rays' own covariances.
 * \throws std::invalid_argument for a cov_rays that is not 18x18 or alpha outside (0, 1). */
TRayIncidenceTest threeRaysMeet(const TUncertainLine3& ray1, const TUncertainLine3& ray2,
                                const TUncertainLine3& ray3, double alpha, const MatX* cov_rays = nullptr);
/** threeRaysMeet() at a level whose critical values are computed already (TSignificance::At). */
TRayIncidenceTest threeRaysMeet(const TUncertainLine3& ray1, const TUncertainLine3& ray2,
                                const TUncertainLine3& ray3, const TSignificance& level,
                                const MatX* cov_rays = nullptr);
}  // namespace immslam::geometry
