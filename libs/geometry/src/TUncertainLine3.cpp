/* imm-monoslam — uncertain Plücker lines. */
#include <immslam/geometry/TUncertainLine3.h>
#include <immslam/geometry/construction_matrices.h>
#include <immslam/geometry/spherical_normalization.h>

#include <cmath>
#include <stdexcept>

namespace immslam::geometry
{
TUncertainLine3 TUncertainLine3::FromPointDirection(const Vec3& p, const Vec3& d)
{
  Vec6 L;
  L << d, p.cross(d);
  return TUncertainLine3(L);
}

double TUncertainLine3::plueckerResidual() const
{
  return L.head<3>().dot(L.tail<3>()) / L.squaredNorm();
}

Vec3 TUncertainLine3::pointClosestToOrigin() const
{
  const double n2 = L.head<3>().squaredNorm();
  if (!(n2 > 1e-24 * L.squaredNorm()))
    throw std::runtime_error(
        "immslam/geometry/TUncertainLine3.cpp: pointClosestToOrigin() of a line at infinity");
  // With L0 = p x Lh and p orthogonal to Lh: Lh x L0 = |Lh|^2 p.
  return L.head<3>().cross(L.tail<3>()) / n2;
}

double TUncertainLine3::distanceTo(const Vec3& p) const
{
  const double n = L.head<3>().norm();
  if (!(n > 1e-12 * L.norm()))
    throw std::runtime_error("immslam/geometry/TUncertainLine3.cpp: distanceTo() a line at infinity");
  // p x Lh - L0 = (p - q) x Lh for any point q of the line.
  return (p.cross(L.head<3>()) - L.tail<3>()).norm() / n;
}

TUncertainLine3 TUncertainLine3::normalized() const
{
  Mat6 J;
  const Vec6 ls = sphericallyNormalized<6>(L, &J);
  const Vec6 dl = dualLine(ls).normalized();
  const Mat6 P = Mat6::Identity() - dl * dl.transpose();
  const Mat6 JP = P * J;
  Mat6 c = JP * cov * JP.transpose();
  c = 0.5 * (c + c.transpose()).eval();
  return TUncertainLine3(ls, c);
}

TUncertainLine3 TUncertainLine3::plueckerCorrected() const
{
  // (L + t DL)^T D (L + t DL) = c + 2 t |L|^2 + t^2 c with c = L^T D L and |DL| = |L|:
  // the root of smallest magnitude is t = -c / (|L|^2 + sqrt(|L|^4 - c^2)) (|c| <= |L|^2 always).
  const double n2 = L.squaredNorm();
  const double c = 2.0 * L.head<3>().dot(L.tail<3>());
  const double t = -c / (n2 + std::sqrt(std::max(0.0, n2 * n2 - c * c)));
  TUncertainLine3 out(L + t * dualLine(L), cov);
  return out.normalized();
}
}  // namespace immslam::geometry
