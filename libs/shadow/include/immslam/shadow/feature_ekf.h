/* imm-monoslam — the shadow filter's per-feature EKF (MonoSLAMBOT paper, Sec. III, eqs. 1-5): a
 * bearing-only tracker of one point in homogeneous coordinates in the current camera frame with a
 * constant velocity in the "feature frame" (camera axes translated to the feature). */
#pragma once

#include <immslam/camera/CCameraModel.h>
#include <immslam/math/types.h>

namespace immslam::shadow
{
using Vec7 = Eigen::Matrix<double, 7, 1>;
using Mat7 = Eigen::Matrix<double, 7, 7>;
using Mat27 = Eigen::Matrix<double, 2, 7>;
using Mat76 = Eigen::Matrix<double, 7, 6>;
using Mat73 = Eigen::Matrix<double, 7, 3>;

/** Offsets in the state of eq. (1): x = (x, y, z, w | ux, uy, uz). */
constexpr int kH = 0, kW = 3, kVel = 4, kShadowDim = 7;

/** The state of eq. (1) and its covariance, in homogeneous form.
 *
 * - \f$ \mathbf h = (x, y, z, w) \f$: the feature's homogeneous coordinates in the current camera
 *   frame \f$ C_k \f$, \f$ \mathbf p = (x, y, z)/w \f$.
 * - \f$ \mathbf u = w\,\mathbf v \f$: the feature's velocity \f$ \mathbf v \f$ in the feature frame
 *   \f$ F_k \f$ (camera axes; SLAM length units per frame, doc/conventions.md) carried with the same
 *   homogeneous factor as the position, so that \f$ (\mathbf h, \mathbf u) \f$ is one homogeneous
 *   7-vector: scaling it changes neither \f$ \mathbf p \f$ nor \f$ \mathbf v = \mathbf u / w \f$.
 *   With this choice the motion model (2) is *linear* in the state (shadowTransition()) and the
 *   measurement depends only on the ray \f$ (x, y, z) \f$, which the image pins down to a pixel: the
 *   EKF is then nearly linear-Gaussian even when the distance is unknown (w near 0), whereas the
 *   Euclidean velocity of eq. (1) makes \f$ w\mathbf v \f$ a product of two poorly known states and
 *   the EKF grossly over-confident (measured in shadow_consistency_unittest: average NEES in the
 *   thousands, 64 % of position errors inside +-3 sigma). Like the modified polar coordinates of
 *   bearing-only tracking, the unobservable scale stays decoupled.
 * - Gauge: the paper leaves the homogeneous scale free; we fix \f$ |(x, y, z)| = 1 \f$ after every
 *   prediction and update (normalizeGauge()), so \f$ (x, y, z) \f$ is the unit viewing ray and w the
 *   inverse *distance* — exactly the inverse-depth parametrization's \f$ \rho \f$ (w = 0: a point at
 *   infinity; w < 0 is unphysical but allowed, as rho in inverse-depth SLAM). The covariance then
 *   has the gauge direction \f$ \mathbf x \f$ in its null space (rank 6). */
struct TShadowState
{
  Vec7 x = (Vec7() << 0, 0, 1, 1, 0, 0, 0).finished();
  Mat7 P = Mat7::Identity();

  /** (x, y, z, w). */
  Vec4 h() const { return x.head<4>(); }
  /** The homogeneous velocity u = w v (current camera axes). */
  Vec3 u() const { return x.segment<3>(kVel); }
};

/** Initialisation from the first observation uv (undelayed, as inverse depth): the ray
 * \f$ \mathbf m = \mathrm{unproject}(uv) \f$ with covariance \f$ J \sigma^2 J^\top \f$, w ~ N(rho0,
 * sigmaRho^2) (the prior's 95 % region should include 0, i.e. infinity), v ~ N(0, sigmaV^2 I)
 * independent of w, so u = w v has mean 0, covariance \f$ (\rho_0^2 + \sigma_\rho^2)\sigma_v^2 I \f$
 * and no correlation with w.
 * \param sigmaPx pixel noise; \param sigmaV velocity prior std (length/frame). */
TShadowState initialiseShadowState(const camera::CCameraModel& cam, const Vec2& uv, double sigmaPx,
                                   double rho0, double sigmaRho, double sigmaV);

/** Motion model, eq. (2): the feature moves by \f$ (\mathbf v + \mathbf V)\,dt \f$ in \f$ F_k \f$, then
 * position and velocity are re-expressed in the new camera frame with the increment (t, dq)
 * (\f$ p_{C_{k-1}} = R(dq) p_{C_k} + t \f$, TCameraMotion). In the homogeneous form
 * (\f$ \mathbf u = w\mathbf v \f$):
 * \f[ \mathbf h'_{xyz} = R^\top\big(\mathbf h_{xyz} + (\mathbf u + w\mathbf V)\,dt - w\,\mathbf t\big),\quad
 *     w' = w,\quad \mathbf u' = R^\top(\mathbf u + w\mathbf V), \f]
 * linear in the state (a point at infinity, w = 0, only rotates). \f$ \mathbf V \f$ is the velocity
 * impulse of an acceleration noise (as the motion models do). Not gauge-normalized.
 * \param J_x   d x'/d x (7x7);
 * \param J_inc d x'/d [dt; dtheta] of the increment's perturbation (7x6):
 *              \f$ \partial\mathbf h'_{xyz}/\partial\delta t = -w R^\top \f$,
 *              \f$ \partial\mathbf h'_{xyz}/\partial\delta\theta = [\mathbf h'_{xyz}]_\times \f$,
 *              \f$ \partial\mathbf u'/\partial\delta\theta = [\mathbf u']_\times \f$;
 * \param J_V   d x'/d V at V = 0 (7x3). */
Vec7 shadowTransition(const Vec7& x, double dt, const Vec3& t, const Vec4& dq, Mat7* J_x = nullptr,
                      Mat76* J_inc = nullptr, Mat73* J_V = nullptr);

/** Measurement model, eqs. (3)-(5) with the real camera model (distortion included): the pixel of
 * the ray \f$ \mathbf h_{xyz} \f$ (only its direction matters, so w does not enter).
 * \param J optional d uv / d x (2x7).
 * \return false if the ray is not in front of the camera or outside the model's domain. */
bool shadowMeasurement(const camera::CCameraModel& cam, const Vec7& x, Vec2& uv, Mat27* J = nullptr);

/** The gauge \f$ |(x, y, z)| = 1 \f$: \f$ \mathbf x / |\mathbf h_{xyz}| \f$ (the whole homogeneous
 * 7-vector, so p and v are unchanged). \param J optional Jacobian (7x7); \f$ J\,\mathbf x = 0 \f$. */
Vec7 normalizeGauge(const Vec7& x, Mat7* J = nullptr);

/** Predicts a state over one frame: eq. (2), process noise \f$ J_{inc} \Sigma_{inc} J_{inc}^\top +
 * J_V\, \sigma_a^2 dt^2 I\, J_V^\top \f$, then normalizeGauge(). \param sigmaAccel acceleration noise
 * (length/frame^2). */
void predictShadowState(TShadowState& s, double dt, const Vec3& t, const Vec4& dq, const Mat6& cov_increment,
                        double sigmaAccel);

/** EKF update with one pixel measurement (eqs. 3-5) by bayes::ekfUpdate, then normalizeGauge().
 * \param nis optional output: the normalized innovation squared at the prior.
 * \return false (state unchanged) if the prediction is not projectable or S is not PD. */
bool updateShadowState(TShadowState& s, const camera::CCameraModel& cam, const Vec2& z, double sigmaPx,
                       double* nis = nullptr);

/** Innovation covariance \f$ S = J P J^\top + \sigma^2 I \f$ and the predicted pixel.
 * \return false if not projectable. */
bool shadowInnovation(const TShadowState& s, const camera::CCameraModel& cam, double sigmaPx, Vec2& h, Mat2& S);

/** Euclidean position \f$ \mathbf p = \mathbf h_{xyz} / w \f$ in the current camera frame, with w
 * clamped to >= wMin (points at or beyond infinity are placed at distance 1/wMin).
 * \param cov optional first-order covariance; \param J_p_x optional 3x7 Jacobian. */
Vec3 shadowPosition(const TShadowState& s, double wMin = 1e-3, Mat3* cov = nullptr,
                    Eigen::Matrix<double, 3, 7>* J_p_x = nullptr);

/** Euclidean velocity \f$ \mathbf v = \mathbf u / w \f$ (current camera axes, length per frame), w
 * clamped to >= wMin. \param cov optional first-order covariance; \param J_v_x optional 3x7 Jacobian. */
Vec3 shadowVelocity(const TShadowState& s, double wMin = 1e-3, Mat3* cov = nullptr,
                    Eigen::Matrix<double, 3, 7>* J_v_x = nullptr);
}  // namespace immslam::shadow
