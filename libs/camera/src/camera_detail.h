/* imm-monoslam — helpers shared by the camera models' sources (not installed API). */
#pragma once

#include <immslam/math/bearing.h>
#include <immslam/math/types.h>

#include <cmath>
#include <string>

namespace immslam::camera::detail
{
/** True if p_C is in front of the camera: z > 1e-9 |p_C| (no square root). */
inline bool inFront(const Vec3& p)
{
  const double z = p.z();
  return z > 0 && z * z > 1e-18 * p.squaredNorm() && std::isfinite(p.squaredNorm());
}

/** d(x/z, y/z)/dp for p = (x, y, z), 2x3. */
inline void normalizedJacobian(const Vec3& p, Mat23& J)
{
  const double iz = 1.0 / p.z();
  J << iz, 0, -p.x() * iz * iz,  //
      0, iz, -p.y() * iz * iz;
}

/** The bearing of the normalized point n = (x, y) (ray (x, y, 1)) and, if J_b_uv is given,
 * J_b_uv = d(b)/d(n) * J_n_uv. */
inline math::Bearing bearingOfNormalized(const Vec2& n, const Mat2& J_n_uv, Mat32* J_b_uv)
{
  const Vec3 ray(n.x(), n.y(), 1.0);
  const double len = ray.norm();
  const Vec3 b = ray / len;
  if (J_b_uv)
  {
    // Chain rule: d(ray/|ray|)/d(ray) = (I - b b^T)/|ray|, d(ray)/d(n) = [I2; 0].
    const Mat3 J_b_ray = (Mat3::Identity() - b * b.transpose()) / len;
    *J_b_uv = J_b_ray.leftCols<2>() * J_n_uv;
  }
  return math::Bearing(b);
}

/** Throws std::runtime_error naming the model unless s is a positive finite scale factor. */
void checkScale(double s, const std::string& model);

/** Shortest decimal text that reads back to exactly the same double (locale independent). */
std::string exactText(double v);

/** A pixel coordinate after resampling by s (pixel-centre convention): s (c + 0.5) - 0.5. */
inline double scalePixel(double c, double s) { return s * (c + 0.5) - 0.5; }

/** An image size after resampling by s: round(s n), at least 1. */
int scaleSize(int n, double s);
}  // namespace immslam::camera::detail
