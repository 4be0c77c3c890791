/* imm-monoslam — random rotations and vectors for tests and simulations (like numerical_jacobian.h,
 * a helper of the test suites, kept once here). */
#pragma once

#include <immslam/math/types.h>

#include <random>

namespace immslam::math
{
/** A unit quaternion [qw qx qy qz] uniformly distributed over rotations (normalized 4-D Gaussian). */
inline Vec4 randomQuat(std::mt19937& rng)
{
  std::normal_distribution<double> n;
  return Vec4(n(rng), n(rng), n(rng), n(rng)).normalized();
}

/** A vector of three independent N(0, s^2) components. */
inline Vec3 randomVec3(std::mt19937& rng, double s = 1.0)
{
  std::normal_distribution<double> n(0, s);
  return Vec3(n(rng), n(rng), n(rng));
}
}  // namespace immslam::math
