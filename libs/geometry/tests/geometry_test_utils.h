/* Shared helpers of the geometry tests: random entities, covariances and sampling. */
#pragma once

#include <immslam/geometry/hypothesis_tests.h>
#include <immslam/geometry/join_meet.h>
#include <immslam/math/quaternion.h>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <cmath>
#include <functional>
#include <iostream>
#include <random>

namespace immslam::geometry::test
{
using Rng = std::mt19937_64;

inline VecX randn(Rng& rng, int n, double s = 1.0)
{
  std::normal_distribution<double> nd(0, s);
  VecX v(n);
  for (int i = 0; i < n; ++i) v[i] = nd(rng);
  return v;
}
inline double uniform(Rng& rng, double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); }
inline Vec3 randomUnit(Rng& rng) { return Vec3(randn(rng, 3)).normalized(); }

/** Random SPD covariance R diag(s_i^2) R^T with s_i in [smin, smax]. */
inline MatX randomCov(Rng& rng, int n, double smin, double smax)
{
  const Eigen::HouseholderQR<MatX> qr(MatX(randn(rng, n * n).reshaped(n, n)));
  const MatX Q = qr.householderQ();
  VecX s2(n);
  for (int i = 0; i < n; ++i) s2[i] = std::pow(uniform(rng, smin, smax), 2);
  return Q * s2.asDiagonal() * Q.transpose();
}

/** A square root of a (possibly singular) covariance: S = B B^T. */
inline MatX covSqrt(const MatX& S)
{
  const Eigen::SelfAdjointEigenSolver<MatX> es(0.5 * (S + S.transpose()));
  return es.eigenvectors() * es.eigenvalues().cwiseMax(0).cwiseSqrt().asDiagonal();
}

inline VecX sample(Rng& rng, const VecX& mean, const MatX& sqrtCov)
{
  return mean + sqrtCov * randn(rng, static_cast<int>(sqrtCov.cols()));
}

inline Vec4 randomPoint(Rng& rng)
{
  Vec4 X;
  X << randn(rng, 3, 2.0), uniform(rng, 0.3, 2.0);
  return X;
}
inline Vec4 randomPlane(Rng& rng) { return Vec4(randn(rng, 4)); }
inline Vec6 randomLine(Rng& rng) { return joinPoints(randomPoint(rng), randomPoint(rng)); }

/** Prints a measured rejection rate (shown in the test log). */
inline void reportRate(const char* what, int rejected, int trials)
{
  std::cout << "[ rate     ] " << what << ": " << rejected << " / " << trials << " = "
            << 100.0 * rejected / trials << " %\n";
}
inline TUncertainPoint3 noisyPoint(Rng& rng, const Vec3& p, const Mat3& cov)
{
  return TUncertainPoint3::FromEuclidean(sample(rng, p, covSqrt(cov)), cov);
}
inline Vec3 randomPerpendicular(Rng& rng, const Vec3& u) { return u.cross(randomUnit(rng)).normalized(); }

/** Runs `trial` n times, each returning the test; counts rejections (invalid tests fail the test). */
inline int countRejections(int n, const std::function<THypothesisTest()>& trial, int* invalid = nullptr)
{
  int rejected = 0, bad = 0;
  for (int i = 0; i < n; ++i)
  {
    const THypothesisTest r = trial();
    if (!r.valid) ++bad;
    if (r.rejected()) ++rejected;
  }
  if (invalid) *invalid = bad;
  return rejected;
}
}  // namespace immslam::geometry::test
