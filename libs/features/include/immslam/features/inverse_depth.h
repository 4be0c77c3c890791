/* imm-monoslam — point features: inverse-depth (6-D) and Euclidean XYZ (3-D) parametrizations.
 *
 * Inverse depth (Montiel, Civera & Davison, RSS 2006; Civera et al. T-RO 2008 = the IMM paper's
 * refs. [14], [4]): y = (x0, y0, z0, theta, phi, rho), anchored at the camera centre of the first
 * observation, \f$ p_W = x_0 + \tfrac{1}{\rho} m(\theta,\phi) \f$ with
 * \f$ m = (\cos\phi\sin\theta, -\sin\phi, \cos\phi\cos\theta) \f$ (math::Bearing). Undelayed
 * initialisation from one observation with a prior on rho whose 95 % region includes rho = 0
 * (infinity). Conversion to XYZ when the linearity index is small (Civera, Davison & Montiel,
 * ICRA 2007 = the IMM paper's ref. [3]).
 *
 * Every Jacobian here is checked against a numerical one in features_unittest. */
#pragma once

#include <immslam/math/bearing.h>
#include <immslam/math/types.h>

namespace immslam::features
{
using Mat36 = Eigen::Matrix<double, 3, 6>;
using Mat63 = Eigen::Matrix<double, 6, 3>;
using Mat64 = Eigen::Matrix<double, 6, 4>;

/** Euclidean point of an inverse-depth feature, \f$ x_0 + m(\theta,\phi)/\rho \f$.
 * \param J_y d(p_W)/dy (3x6). rho must be non-zero. */
Vec3 inverseDepthToPoint(const Vec6& y, Mat36* J_y = nullptr);

/** Direction (homogeneous point) of an inverse-depth feature in the camera frame:
 * \f$ h^C = R_{CW}\,(\rho\,(x_0 - r) + m(\theta,\phi)) \f$ — the measurement model's 3-D part, well
 * defined for rho = 0 (points at infinity) and proportional to the camera-frame point.
 * \param r camera centre r_W_C, \param q orientation q_W_C ([qw qx qy qz]).
 * \param J_y dh/dy (3x6), \param J_r dh/dr (3x3), \param J_q dh/dq (3x4). */
Vec3 inverseDepthInCamera(const Vec6& y, const Vec3& r, const Vec4& q, Mat36* J_y = nullptr,
                          Mat3* J_r = nullptr, Mat34* J_q = nullptr);

/** Camera-centred form of the measurement's 3-D part: with the feature expressed in the current
 * camera frame (robocentric state, the camera at the origin), \f$ h^C = \rho\, x_0 + m(\theta,\phi) \f$.
 * \param J_y dh/dy (3x6). */
Vec3 inverseDepthRay(const Vec6& y, Mat36* J_y = nullptr);

/** A point re-expressed after a camera motion: the camera moved by (t, dq) in its own frame,
 * \f$ p_{C_k} = R(dq)\, p_{C_{k+1}} + t \f$, so \f$ p' = R(dq)^\top (p - t) \f$.
 * \param J_p dp'/dp (3x3), \param J_t dp'/dt (3x3), \param J_dq dp'/d(dq) (3x4). */
Vec3 transformPoint(const Vec3& p, const Vec4& dq, const Vec3& t, Mat3* J_p = nullptr, Mat3* J_t = nullptr,
                    Mat34* J_dq = nullptr);

/** An inverse-depth feature re-expressed after the same camera motion: the anchor moves like a
 * point, the ray direction rotates, rho is unchanged (it is the inverse distance from the anchor).
 * \param J_y dy'/dy (6x6), \param J_t dy'/dt (6x3), \param J_dq dy'/d(dq) (6x4). */
Vec6 transformInverseDepth(const Vec6& y, const Vec4& dq, const Vec3& t, Mat6* J_y = nullptr, Mat63* J_t = nullptr,
                           Mat64* J_dq = nullptr);

/** Euclidean feature in the camera frame: \f$ R_{CW}(p_W - r) \f$ with Jacobians. */
Vec3 xyzInCamera(const Vec3& p_W, const Vec3& r, const Vec4& q, Mat3* J_p = nullptr,
                 Mat3* J_r = nullptr, Mat34* J_q = nullptr);

/** Undelayed initialisation: the inverse-depth feature of a viewing ray.
 * \f$ y = (r,\; \theta(R_{WC} b),\; \phi(R_{WC} b),\; \rho_0) \f$.
 * \param b_C the ray in the camera frame (any scale, e.g. CCameraModel::unproject).
 * \param J_r dy/dr (6x3), \param J_q dy/dq (6x4), \param J_b dy/d(b_C) (6x3); dy/drho0 = e6. */
Vec6 initInverseDepth(const Vec3& r, const Vec4& q, const Vec3& b_C, double rho0,
                      Mat63* J_r = nullptr, Mat64* J_q = nullptr, Mat63* J_b = nullptr);

/** Linearity index of the inverse-depth -> depth mapping (ref. [3]):
 * \f$ L = \frac{4\sigma_\rho}{\rho^2} \frac{|\cos\alpha|}{\|p_W - r\|} \f$ with alpha the angle between
 * the feature's ray m and the ray from the current camera centre r to the point. Convert to XYZ
 * when L is below a threshold (0.1 in ref. [3]). Returns +inf when rho <= 0. */
double linearityIndex(const Vec6& y, double sigmaRho, const Vec3& r);
}  // namespace immslam::features
