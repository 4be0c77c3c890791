/* Helpers shared by the SLAM filter's tests. */
#pragma once

#include <immslam/math/types.h>

#include <random>

namespace immslam::slam::test
{
/** A dense random covariance A A^T (entries of A ~ N(0, 0.01)). */
inline MatX randomCovariance(int n, std::mt19937& rng)
{
  std::normal_distribution<double> g;
  MatX A(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) A(i, j) = 0.1 * g(rng);
  return A * A.transpose();
}
}  // namespace immslam::slam::test
