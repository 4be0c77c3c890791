/* imm-monoslam — an uncertain 3D plane in homogeneous coordinates (shadow-filter paper, eq. (8)). */
#pragma once

#include <immslam/geometry/geometry_types.h>

namespace immslam::geometry
{
/** An uncertain 3D plane: homogeneous 4-vector \f$ \mathbf A = (\mathbf A_h^\top, A_0)^\top \f$ with
 * its 4x4 covariance. A point X lies on A iff \f$ \mathbf A^\top \mathbf X = 0 \f$, i.e. for
 * Euclidean points \f$ \mathbf A_h^\top \mathbf x + A_0 = 0 \f$: \f$ \mathbf A_h \f$ is the normal
 * (the homogeneous part), \f$ -A_0/|\mathbf A_h| \f$ the signed distance of the plane from the
 * origin along the unit normal.
 * \sa join() (point ^ line, eq. (8)), meet() */
struct TUncertainPlane3
{
  Vec4 A = Vec4(0, 0, 1, 0);  ///< (A_h, A_0): the plane z = 0 by default
  Mat4 cov = Mat4::Zero();    ///< covariance of A

  TUncertainPlane3() = default;
  /** From a homogeneous vector and its covariance (default: exact). */
  explicit TUncertainPlane3(const Vec4& A_, const Mat4& cov_ = Mat4::Zero()) : A(A_), cov(cov_) {}

  /** The exact plane through p with normal n: \f$ (\mathbf n, -\mathbf n^\top \mathbf p) \f$. */
  static TUncertainPlane3 FromPointNormal(const Vec3& p, const Vec3& n);

  /** Unit normal \f$ \mathbf A_h / |\mathbf A_h| \f$.
   * \throws std::runtime_error for the plane at infinity (\f$ \mathbf A_h = 0 \f$). */
  Vec3 unitNormal() const;

  /** Signed Euclidean distance of p from the plane, \f$ (\mathbf A_h^\top \mathbf p + A_0) /
   * |\mathbf A_h| \f$. \throws std::runtime_error for the plane at infinity. */
  double signedDistance(const Vec3& p) const;

  /** Spherically normalized copy (A / |A| and \f$ J\Sigma J^\top \f$, see sphericallyNormalized()).
   * The sign is kept. \throws std::runtime_error for a zero or non-finite A. */
  TUncertainPlane3 normalized() const;
};
}  // namespace immslam::geometry
