/* imm-monoslam — uncertain homogeneous planes. */
#include <immslam/geometry/TUncertainPlane3.h>
#include <immslam/geometry/spherical_normalization.h>

#include <stdexcept>

namespace immslam::geometry
{
TUncertainPlane3 TUncertainPlane3::FromPointNormal(const Vec3& p, const Vec3& n)
{
  Vec4 A;
  A << n, -n.dot(p);
  return TUncertainPlane3(A);
}

Vec3 TUncertainPlane3::unitNormal() const
{
  const double n = A.head<3>().norm();
  if (!(n > 1e-12 * A.norm()))
    throw std::runtime_error("immslam/geometry/TUncertainPlane3.cpp: unitNormal() of the plane at infinity");
  return A.head<3>() / n;
}

double TUncertainPlane3::signedDistance(const Vec3& p) const
{
  const double n = A.head<3>().norm();
  if (!(n > 1e-12 * A.norm()))
    throw std::runtime_error(
        "immslam/geometry/TUncertainPlane3.cpp: signedDistance() to the plane at infinity");
  return (A.head<3>().dot(p) + A[3]) / n;
}

TUncertainPlane3 TUncertainPlane3::normalized() const
{
  Mat4 J;
  const Vec4 as = sphericallyNormalized<4>(A, &J);
  return TUncertainPlane3(as, J * cov * J.transpose());
}
}  // namespace immslam::geometry
