/* imm-monoslam — uncertain homogeneous 3D points. */
#include <immslam/geometry/TUncertainPoint3.h>
#include <immslam/geometry/spherical_normalization.h>

#include <cmath>
#include <stdexcept>

namespace immslam::geometry
{
TUncertainPoint3 TUncertainPoint3::FromEuclidean(const Vec3& p, const Mat3& cov_p)
{
  TUncertainPoint3 out;
  out.X << p, 1.0;
  out.cov.topLeftCorner<3, 3>() = cov_p;
  return out;
}

TUncertainPoint3 TUncertainPoint3::AtInfinity(const Vec3& d, const Mat3& cov_d)
{
  TUncertainPoint3 out;
  out.X << d, 0.0;
  out.cov.topLeftCorner<3, 3>() = cov_d;
  return out;
}

Vec3 TUncertainPoint3::euclidean(Mat3* cov_p, Mat34* J_p_X) const
{
  const double h = X[3];
  if (!(std::abs(h) > 1e-12 * X.norm()))
    throw std::runtime_error(
        "immslam/geometry/TUncertainPoint3.cpp: euclidean() of a point at infinity (Xh = 0)");
  const Vec3 p = X.head<3>() / h;
  if (cov_p || J_p_X)
  {
    // Chain rule: p = X0 / Xh -> dp/dX0 = I/Xh, dp/dXh = -X0/Xh^2 = -p/Xh.
    Mat34 J;
    J.leftCols<3>() = Mat3::Identity() / h;
    J.col(3) = -p / h;
    if (cov_p) *cov_p = J * cov * J.transpose();
    if (J_p_X) *J_p_X = J;
  }
  return p;
}

TUncertainPoint3 TUncertainPoint3::normalized() const
{
  Mat4 J;
  Vec4 xs = sphericallyNormalized<4>(X, &J);
  if (xs[3] < 0)
  {
    xs = -xs;
    J = -J;
  }
  return TUncertainPoint3(xs, J * cov * J.transpose());
}
}  // namespace immslam::geometry
