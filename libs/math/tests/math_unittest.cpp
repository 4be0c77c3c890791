/* Tests: quaternion Jacobians vs numerical, chi-square quantiles, log-likelihoods. */
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <gtest/gtest.h>
#include <immslam/math/bearing.h>
#include <immslam/math/chi2.h>
#include <immslam/math/gaussian.h>
#include <immslam/math/numerical_jacobian.h>
#include <immslam/math/parallel.h>
#include <immslam/math/quaternion.h>
#include <immslam/math/random_samples.h>

#include <mutex>
#include <random>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

using namespace immslam;
using namespace immslam::math;

namespace
{
}  // namespace

TEST(Quaternion, RotateMatchesEigenAndJacobians)
{
  std::mt19937 rng(1);
  for (int t = 0; t < 50; ++t)
  {
    const Vec4 q = randomQuat(rng);
    const Vec3 a = randomVec3(rng);
    Mat34 Jq;
    Mat3 Ja;
    const Vec3 r = quatRotate(q, a, &Jq, &Ja);
    EXPECT_LT((r - toEigen(q) * a).norm(), 1e-12);
    EXPECT_LT((Ja - quatToRotation(q)).norm(), 1e-12);
    VecX x(7);
    x << q, a;
    const MatX Jn = numericalJacobian(
        [](const VecX& v) -> VecX { return quatRotate(v.head<4>(), v.tail<3>()); }, x);
    EXPECT_LT((Jn.leftCols(4) - Jq).norm(), 1e-7);
    EXPECT_LT((Jn.rightCols(3) - Ja).norm(), 1e-7);
  }
}

TEST(Quaternion, MultiplyMatchesEigenAndJacobians)
{
  std::mt19937 rng(2);
  for (int t = 0; t < 50; ++t)
  {
    const Vec4 q1 = randomQuat(rng), q2 = randomQuat(rng);
    Mat4 J1, J2;
    const Vec4 r = quatMultiply(q1, q2, &J1, &J2);
    EXPECT_LT((r - fromEigen(toEigen(q1) * toEigen(q2))).norm(), 1e-12);
    VecX x(8);
    x << q1, q2;
    const MatX Jn = numericalJacobian(
        [](const VecX& v) -> VecX { return quatMultiply(v.head<4>(), v.tail<4>()); }, x);
    EXPECT_LT((Jn.leftCols(4) - J1).norm(), 1e-8);
    EXPECT_LT((Jn.rightCols(4) - J2).norm(), 1e-8);
  }
}

TEST(Quaternion, ExpLogRoundTripAndJacobian)
{
  std::mt19937 rng(3);
  for (double scale : {1e-9, 1e-5, 1e-3, 0.1, 1.0, 2.5})
  {
    for (int t = 0; t < 20; ++t)
    {
      const Vec3 w = randomVec3(rng, scale);
      if (w.norm() >= M_PI) continue;
      Mat43 J;
      const Vec4 q = quatFromRotationVector(w, &J);
      EXPECT_NEAR(q.norm(), 1.0, 1e-12);
      EXPECT_LT((quatToRotationVector(q) - w).norm(), 1e-9 + 1e-9 * w.norm());
      const Eigen::AngleAxisd aa(w.norm(), w.norm() > 0 ? Vec3(w.normalized()) : Vec3::UnitX());
      EXPECT_LT((quatToRotation(q) - aa.toRotationMatrix()).norm(), 1e-12);
      const MatX Jn = numericalJacobian(
          [](const VecX& v) -> VecX { return quatFromRotationVector(v); }, w, 1e-7);
      EXPECT_LT((Jn - J).norm(), 1e-6) << "scale " << scale;
    }
  }
}

TEST(Quaternion, NormalizeJacobian)
{
  std::mt19937 rng(4);
  const Vec4 q = 1.7 * randomQuat(rng);
  Mat4 J;
  const Vec4 qn = quatNormalized(q, &J);
  EXPECT_NEAR(qn.norm(), 1.0, 1e-15);
  const MatX Jn =
      numericalJacobian([](const VecX& v) -> VecX { return quatNormalized(v); }, q);
  EXPECT_LT((Jn - J).norm(), 1e-8);
}

TEST(Chi2, QuantilesMatchTables)
{
  EXPECT_NEAR(chi2Quantile(0.95, 1), 3.841459, 1e-5);
  EXPECT_NEAR(chi2Quantile(0.95, 2), 5.991465, 1e-5);
  EXPECT_NEAR(chi2Quantile(0.95, 3), 7.814728, 1e-5);
  EXPECT_NEAR(chi2Quantile(0.99, 6), 16.811894, 1e-5);
  EXPECT_NEAR(chi2Quantile(0.025, 150), 117.9845, 1e-3);
  EXPECT_NEAR(chi2Quantile(0.975, 150), 185.8004, 1e-3);
  for (int dof : {1, 3, 7, 40})
    for (double p : {0.01, 0.5, 0.95})
      EXPECT_NEAR(chi2Cdf(chi2Quantile(p, dof), dof), p, 1e-10);
}

TEST(Gaussian, LogLikelihoodMatchesClosedForm)
{
  MatX S(2, 2);
  S << 4, 1, 1, 3;
  VecX nu(2);
  nu << 0.5, -1.2;
  double d2 = 0;
  const double ll = gaussianLogLikelihood(nu, S, &d2);
  const double d2ref = nu.dot(S.inverse() * nu);
  EXPECT_NEAR(d2, d2ref, 1e-12);
  EXPECT_NEAR(ll, -0.5 * (d2ref + std::log(S.determinant()) + 2 * std::log(2 * M_PI)), 1e-12);
  MatX bad = -S;
  EXPECT_EQ(gaussianLogLikelihood(nu, bad), -std::numeric_limits<double>::infinity());
}

TEST(Gaussian, LogSumExpIsStable)
{
  VecX v(3);
  v << -1000, -1001, -1002;
  EXPECT_NEAR(logSumExp(v), -1000 + std::log(1 + std::exp(-1.0) + std::exp(-2.0)), 1e-12);
}

TEST(Bearing, AnglesRoundTripAndJacobians)
{
  std::mt19937 rng(5);
  for (int t = 0; t < 50; ++t)
  {
    Vec3 v = randomVec3(rng);
    if (std::hypot(v.x(), v.z()) < 0.1) continue;
    const Bearing b(v);
    EXPECT_NEAR(b.unitVector().norm(), 1.0, 1e-15);
    Mat23 J;
    const Vec2 tp = Bearing::AzimuthElevation(v, &J);
    EXPECT_LT((Bearing::DirectionFromAngles(tp[0], tp[1]) - b.unitVector()).norm(), 1e-12);
    const MatX Jn = numericalJacobian(
        [](const VecX& x) -> VecX { return Bearing::AzimuthElevation(x); }, v);
    EXPECT_LT((Jn - J).norm(), 1e-7);
    Mat32 Jm;
    Bearing::DirectionFromAngles(tp[0], tp[1], &Jm);
    const MatX Jmn = numericalJacobian(
        [](const VecX& x) -> VecX { return Bearing::DirectionFromAngles(x[0], x[1]); }, tp);
    EXPECT_LT((Jmn - Jm).norm(), 1e-8);
  }
}

TEST(ThreadPool, BackToBackJobsOfEverySizeAndUnevenCosts)
{
  // Many short jobs in a row (the workers spin between them) and indices of very different cost
  // (dynamic scheduling): every index runs exactly once, results do not depend on the thread count.
  std::vector<double> ref;
  for (unsigned n : {1u, 2u, 4u})
  {
    CThreadPool pool(n);
    std::vector<double> all;
    for (int rep = 0; rep < 500; ++rep)
    {
      const int len = 1 + rep % 11;
      std::vector<double> out(len, 0.0);
      pool.parallelFor(rep, rep + len, [&](int i) {
        double s = 0;
        for (int k = 0; k < ((i - rep) % 3 == 0 ? 2000 : 10); ++k) s += std::sin(0.001 * k + i);
        out[i - rep] += s;
      });
      all.insert(all.end(), out.begin(), out.end());
    }
    if (ref.empty())
      ref = all;
    else
      EXPECT_EQ(all, ref) << n << " threads";
  }
}

TEST(ThreadPool, ManyGrowingJobsWithMoreThreadsThanCoresNeitherHangNorRunAnIndexTwice)
{
  // Jobs of 1, 2, 3 indices in turn, back to back, more threads asked for than this machine's 2
  // cores: the pattern that once hung a hand-written pool (a worker late in one job claimed an index
  // of the next). Every index runs exactly once and the test ends (ctest timeout 120 s).
  for (unsigned n : {3u, 4u})
  {
    CThreadPool pool(n);
    std::vector<std::atomic<int>> hits(3);
    long twice = 0;
    for (int rep = 0; rep < 150000; ++rep)
    {
      const int len = 1 + rep % 3;
      for (int i = 0; i < len; ++i) hits[i].store(0, std::memory_order_relaxed);
      pool.parallelFor(0, len, [&](int i) { hits[i].fetch_add(1, std::memory_order_relaxed); });
      for (int i = 0; i < len; ++i) twice += hits[i].load() != 1 ? 1 : 0;
    }
    EXPECT_EQ(twice, 0) << n << " threads";
  }
}

TEST(ThreadPool, LargeRangesCoverEveryIndexOnce)
{
  CThreadPool pool(3);
  std::vector<unsigned char> hits(200000, 0);
  pool.parallelFor(-100000, 100000, [&](int i) { hits[static_cast<std::size_t>(i + 100000)]++; });
  EXPECT_EQ(std::count(hits.begin(), hits.end(), 1), 200000);
}

TEST(ThreadPool, CoversEveryIndexOnceAndPropagatesErrors)
{
  for (unsigned n : {1u, 2u, 3u})
  {
    CThreadPool pool(n);
    for (int rep = 0; rep < 20; ++rep)
    {
      std::vector<int> hits(37, 0);
      pool.parallelFor(0, 37, [&](int i) { hits[i]++; });
      for (int h : hits) EXPECT_EQ(h, 1);
    }
    // The exception itself reaches the caller, the other indices still run, and the pool keeps
    // working after it.
    std::vector<int> ran(10, 0);
    try
    {
      pool.parallelFor(0, 10, [&](int i) {
        if (i == 7) throw std::runtime_error("index 7 failed");
        ran[i]++;
      });
      ADD_FAILURE() << "no exception with " << n << " threads";
    }
    catch (const std::runtime_error& e)
    {
      EXPECT_STREQ(e.what(), "index 7 failed");
    }
    EXPECT_EQ(std::count(ran.begin(), ran.end(), 1), 9) << n << " threads";
    std::vector<int> after(5, 0);
    pool.parallelFor(0, 5, [&](int i) { after[i]++; });
    EXPECT_EQ(after, std::vector<int>(5, 1)) << n << " threads";
  }
}

TEST(ThreadPool, HonoursTheNumberOfThreads)
{
  // size() is what was asked (0: the hardware's); no more than that many indices ever run at once;
  // with one thread every index runs on the caller.
  EXPECT_EQ(CThreadPool(3).size(), 3u);
  EXPECT_EQ(CThreadPool(0).size(), std::max(1u, std::thread::hardware_concurrency()));
  for (unsigned n : {1u, 2u, 3u})
  {
    CThreadPool pool(n);
    std::atomic<int> running{0}, most{0};
    std::mutex m;
    std::set<std::thread::id> ids;
    pool.parallelFor(0, 64, [&](int) {
      const int now = running.fetch_add(1) + 1;
      for (int seen = most.load(); now > seen && !most.compare_exchange_weak(seen, now);) {}
      std::this_thread::sleep_for(std::chrono::microseconds(200));
      {
        std::lock_guard<std::mutex> lk(m);
        ids.insert(std::this_thread::get_id());
      }
      running.fetch_sub(1);
    });
    EXPECT_LE(most.load(), static_cast<int>(n));
    EXPECT_LE(ids.size(), n);
    if (n == 1)
    {
      EXPECT_EQ(ids, std::set<std::thread::id>{std::this_thread::get_id()});
    }
  }
}
