/* imm-monoslam — unit quaternions with analytic Jacobians.
 *
 * Convention (doc/conventions.md): a quaternion is a Vec4 q = [qw qx qy qz] (scalar first, as in
 * Civera et al.'s inverse-depth EKF), Hamilton product, and R(q) rotates vectors of the frame the
 * quaternion is "of" into its parent frame: p_W = R(q_W_C) p_C.
 * Every function fills its Jacobians only when the pointer is non-null (GTSAM's OptionalJacobian
 * idiom). All Jacobians are checked against numerical ones in math_unittest.
 */
#pragma once

#include <immslam/math/types.h>

#include <Eigen/Geometry>

namespace immslam::math
{
/** Rotation matrix of a unit quaternion q = [qw qx qy qz]. */
Mat3 quatToRotation(const Vec4& q);

/** Rotates a by q: \f$ R(q)\,a \f$ using the quadratic form of R(q) (exact for unit q).
 * \param J_q  d(R(q)a)/dq (3x4), derived from the quadratic form, valid for any q.
 * \param J_a  d(R(q)a)/da = R(q). */
Vec3 quatRotate(const Vec4& q, const Vec3& a, Mat34* J_q = nullptr, Mat3* J_a = nullptr);

/** Hamilton product \f$ q_1 \otimes q_2 \f$; both Jacobians are 4x4 and linear in the other factor. */
Vec4 quatMultiply(const Vec4& q1, const Vec4& q2, Mat4* J_q1 = nullptr, Mat4* J_q2 = nullptr);

/** Conjugate [qw -qx -qy -qz] (the inverse of a unit quaternion). */
Vec4 quatConjugate(const Vec4& q);

/** Exponential map: the quaternion of the rotation vector w (angle |w| about w/|w|).
 * \param J_w  dq/dw (4x3); uses the series expansion near |w| = 0. */
Vec4 quatFromRotationVector(const Vec3& w, Mat43* J_w = nullptr);

/** Logarithm: the rotation vector of a unit quaternion (angle in [0, pi]). */
Vec3 quatToRotationVector(const Vec4& q);

/** q / |q| and its Jacobian \f$ (I - \hat q \hat q^\top)/|q| \f$. */
Vec4 quatNormalized(const Vec4& q, Mat4* J_q = nullptr);

/** Conversions to and from Eigen's quaternion type. */
Eigen::Quaterniond toEigen(const Vec4& q);
Vec4 fromEigen(const Eigen::Quaterniond& q);

/** Skew-symmetric matrix [v]x with [v]x a = v x a. */
Mat3 skew(const Vec3& v);
}  // namespace immslam::math
