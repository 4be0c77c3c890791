/* imm-monoslam — an uncertain 3D point in homogeneous coordinates (shadow-filter paper, sec. III-A). */
#pragma once

#include <immslam/geometry/geometry_types.h>

namespace immslam::geometry
{
/** An uncertain 3D point: homogeneous 4-vector \f$ \mathbf X = (\mathbf X_0^\top, X_h)^\top =
 * (X, Y, Z, W)^\top \f$ (Euclidean part first, homogeneous part last, as in the paper's eq. (6)-(7))
 * with its 4x4 covariance. The Euclidean point is \f$ \mathbf X_0 / X_h \f$; \f$ X_h = 0 \f$ is a point
 * at infinity (a direction). Any non-zero multiple of X is the same point.
 * \sa TUncertainLine3, TUncertainPlane3, join(), meet() */
struct TUncertainPoint3
{
  Vec4 X = Vec4(0, 0, 0, 1);  ///< homogeneous coordinates (X0 = X.head<3>(), Xh = X[3])
  Mat4 cov = Mat4::Zero();    ///< covariance of X

  TUncertainPoint3() = default;
  /** From a homogeneous vector and its covariance (default: exact). */
  explicit TUncertainPoint3(const Vec4& X_, const Mat4& cov_ = Mat4::Zero()) : X(X_), cov(cov_) {}

  /** The point (p, 1) with covariance diag(cov_p, 0). */
  static TUncertainPoint3 FromEuclidean(const Vec3& p, const Mat3& cov_p = Mat3::Zero());

  /** The point at infinity (d, 0) in direction d, with covariance diag(cov_d, 0). Joined with a
   * camera centre it gives the viewing ray along d (see viewingRay()). */
  static TUncertainPoint3 AtInfinity(const Vec3& d, const Mat3& cov_d = Mat3::Zero());

  /** Euclidean coordinates \f$ \mathbf p = \mathbf X_0 / X_h \f$.
   * \param cov_p optional output: \f$ J \Sigma_{XX} J^\top \f$ with
   *        \f$ J = \partial\mathbf p/\partial\mathbf X = [\,I_3 / X_h \;\; -\mathbf X_0 / X_h^2\,] \f$.
   * \param J_p_X optional output: that 3x4 Jacobian.
   * \throws std::runtime_error for a point at (or numerically at) infinity,
   *         \f$ |X_h| \le 10^{-12} |\mathbf X| \f$. */
  Vec3 euclidean(Mat3* cov_p = nullptr, Mat34* J_p_X = nullptr) const;

  /** Spherically normalized copy (X / |X| and \f$ J\Sigma J^\top \f$, see sphericallyNormalized()),
   * with the sign chosen so that \f$ X_h \ge 0 \f$.
   * \throws std::runtime_error for a zero or non-finite X. */
  TUncertainPoint3 normalized() const;
};
}  // namespace immslam::geometry
