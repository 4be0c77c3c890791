/* imm-monoslam — viewing directions and Civera's azimuth/elevation angles. */
#include <immslam/math/bearing.h>

#include <cmath>
#include <stdexcept>

namespace immslam::math
{
Bearing::Bearing(const Vec3& v)
{
  const double n = v.norm();
  if (!(n > 0) || !std::isfinite(n)) throw std::invalid_argument("Bearing: zero or non-finite vector");
  m_unit = v / n;
}

Vec2 Bearing::AzimuthElevation(const Vec3& v, Mat23* J_v)
{
  const double x = v.x(), y = v.y(), z = v.z();
  const double rxz2 = x * x + z * z;
  const double rxz = std::sqrt(rxz2);
  const Vec2 out(std::atan2(x, z), std::atan2(-y, rxz));
  if (J_v)
  {
    // theta = atan2(x, z): d/dx = z/rxz2, d/dz = -x/rxz2.
    // phi = atan2(-y, rxz): with n2 = rxz2 + y^2, d/dy = -rxz/n2, d/dx = y x/(rxz n2), d/dz = y z/(rxz n2).
    const double n2 = rxz2 + y * y;
    (*J_v) << z / rxz2, 0, -x / rxz2,  //
        y * x / (rxz * n2), -rxz / n2, y * z / (rxz * n2);
  }
  return out;
}

Vec3 Bearing::DirectionFromAngles(double theta, double phi, Mat32* J)
{
  const double st = std::sin(theta), ct = std::cos(theta), sp = std::sin(phi), cp = std::cos(phi);
  if (J) (*J) << cp * ct, -sp * st, 0, -cp, -cp * st, -sp * ct;
  return Vec3(cp * st, -sp, cp * ct);
}
}  // namespace immslam::math
