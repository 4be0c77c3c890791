/* imm-monoslam — the depth-free static test of a shadow feature: does its current view agree with
 * its first view seen through the camera's relative motion, for SOME distance of the point?
 *
 * Neither paper has it. MonoSLAMBOT's three-ray test (Sec. III-A, eqs. 6-14) needs the camera to
 * translate: with a still or rotating camera every viewing ray passes through one centre and meets
 * every other, so nothing can be rejected and nothing has the power to be accepted. But exactly
 * then a static point's bearing is predicted *without* its depth: through the infinite homography
 * \f$ b_k \propto R_{0k}^\top m_0 \f$ (the IMM paper's rotation model, eq. 3, applied to a ray). This
 * test covers that case with full power, and stays valid when the camera translates by profiling
 * the unknown inverse distance out. */
#pragma once

#include <immslam/camera/CCameraModel.h>
#include <immslam/geometry/hypothesis_tests.h>
#include <immslam/shadow/relative_pose.h>

namespace immslam::shadow
{
/** A later view of a feature for depthFreeTest(): its pixel, the camera's pose in \f$ C_0 \f$ with
 * its covariance, and its time (frames since the first view). */
struct TDepthFreeView
{
  Vec2 uv = Vec2::Zero();
  TUncertainPose T_0j;
  double time = 0;
};

/** Result of depthFreeTest(). */
struct TDepthFreeTest
{
  bool evaluated = false;     ///< every view projectable and S positive definite
  double T = 0;               ///< \f$ \min_w r(w)^\top S(w)^{-1} r(w) \f$
  double threshold = 0;       ///< \f$ \chi^2_{4;1-\alpha} \f$
  bool rejected = false;      ///< T > threshold
  double w = 0;               ///< the inverse distance (in \f$ C_0 \f$) that minimises T
  Vec4 r = Vec4::Zero();      ///< residuals (px) of the two later views at w
  Vec4 g = Vec4::Zero();      ///< \f$ \partial r / \partial w \f$ at w: the epipolar directions (px per unit w)
  Mat4 S = Mat4::Identity();  ///< the residuals' covariance at w
  double tau[2] = {0, 0};     ///< times of the two later views since the first (frames)
};

/** Tests H0: the feature is static, from its first view (pixel uv0, camera \f$ C_0 \f$) and two later
 * views m and k (the intermediate and the current view of the three-ray test), whose relative poses
 * \f$ T_{0m}, T_{0k} \f$ are composed from the SLAM increments, with crossCov_km
 * \f$ = \mathrm{Cov}(\delta_k, \delta_m) \f$ (perturbationTransport).
 *
 * A static point is \f$ X = m_0 / w \f$ in \f$ C_0 \f$ (\f$ m_0 \f$ the unit ray of uv0, w >= 0 its
 * inverse distance), seen in \f$ C_j \f$ along \f$ p_j(w) = R_{0j}^\top (m_0 - w\,t_{0j}) \f$. The
 * residuals \f$ r_j(w) = uv_j - \pi(p_j(w)) \f$, j = m, k, have to first order the joint 4x4 covariance
 * of the pixel noise of the three views (uv0 is shared) and of both poses' [dt; dtheta] errors:
 * \f$ \partial p_j / \partial m_0 = R_{0j}^\top \f$, \f$ \partial p_j / \partial \delta t = -w R_{0j}^\top \f$,
 * \f$ \partial p_j / \partial \delta\theta = [p_j]_\times \f$. The statistic is
 * \f$ T = \min_{0 \le w \le w_{max}} r^\top S^{-1} r \f$ (a grid, then Gauss-Newton steps in w), compared
 * with \f$ \chi^2_{4;1-\alpha} \f$:
 * - camera not translating (\f$ t \approx 0 \f$: the IMM's stationary and rotation modes): r does not
 *   depend on w, T is \f$ \chi^2_4 \f$ with full power against any image motion at zero parallax,
 *   including a point that moved and came back (view m sees it away);
 * - camera translating: the minimum over w absorbs motion along the epipolar lines (one common w),
 *   T is about \f$ \chi^2_3 \f$ and the test is conservative; the three-ray test carries the power.
 * \param sigmaPx pixel noise of each view; \param wMax the largest inverse distance considered. */
TDepthFreeTest depthFreeTest(const camera::CCameraModel& cam, const Vec2& uv0, const TDepthFreeView& vm,
                             const TDepthFreeView& vk, const Mat6& crossCov_km, double sigmaPx, double alpha,
                             double wMax);
/** depthFreeTest() at a level whose critical values are computed already (geometry::TSignificance). */
TDepthFreeTest depthFreeTest(const camera::CCameraModel& cam, const Vec2& uv0, const TDepthFreeView& vm,
                             const TDepthFreeView& vk, const Mat6& crossCov_km, double sigmaPx,
                             const geometry::TSignificance& level, double wMax);

/** Non-centrality of depthFreeTest() for a point whose image moved by d (px) between the views
 * (d = [d_m; d_k]): \f$ \lambda(d) = \min_{|a| \le w_{max}} (d - a g)^\top S^{-1} (d - a g) \f$ (the
 * profile over w absorbs at most \f$ w_{max}\,g \f$ of it), at the test's S and g. */
double depthFreeNoncentrality(const TDepthFreeTest& t, const Vec4& d, double wMax);

/** Probability that depthFreeTest() at level alpha rejects a point whose image moves at a constant
 * speedPx pixels per frame (displaced by speedPx tau_j at view j), in its worst image direction. */
double depthFreeDetectionProbability(const TDepthFreeTest& t, double speedPx, double alpha, double wMax);
/** The same at a level whose critical values are computed already. */
double depthFreeDetectionProbability(const TDepthFreeTest& t, double speedPx, const geometry::TSignificance& level,
                                     double wMax);
}  // namespace immslam::shadow
