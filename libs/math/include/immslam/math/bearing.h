/* imm-monoslam — a viewing direction: a unit 3-vector with its own type (cf. GTSAM's Unit3). */
#pragma once

#include <immslam/math/types.h>

namespace immslam::math
{
/** A unit-norm direction. Azimuth/elevation follow Civera et al.'s inverse-depth papers:
 * \f$ m(\theta,\phi) = (\cos\phi\sin\theta,\; -\sin\phi,\; \cos\phi\cos\theta) \f$, so with the
 * optical frame (x right, y down, z forward) theta turns right and phi turns up. */
class Bearing
{
 public:
  /** The optical axis (0, 0, 1). */
  Bearing() = default;
  /** Normalizes v (which must be non-zero and finite). */
  explicit Bearing(const Vec3& v);

  const Vec3& unitVector() const { return m_unit; }

  /** (theta, phi) of any non-zero vector v (scale invariant) and d(theta,phi)/dv (2x3). */
  static Vec2 AzimuthElevation(const Vec3& v, Mat23* J_v = nullptr);

  /** The unit vector m(theta, phi) and dm/d(theta,phi) (3x2). */
  static Vec3 DirectionFromAngles(double theta, double phi, Mat32* J = nullptr);

 private:
  Vec3 m_unit{0, 0, 1};
};
}  // namespace immslam::math
