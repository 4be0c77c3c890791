/* Tests: association, Umeyama alignment, ATE/RPE, NEES and chi-square bands, confusion
 * matrix, statistics. */
#include <gtest/gtest.h>
#include <immslam/core/TTrajectory.h>
#include <immslam/eval/alignment.h>
#include <immslam/eval/associate.h>
#include <immslam/eval/ate.h>
#include <immslam/eval/classification.h>
#include <immslam/eval/consistency.h>
#include <immslam/eval/rpe.h>
#include <immslam/eval/statistics.h>
#include <immslam/math/numerical_jacobian.h>
#include <immslam/math/quaternion.h>
#include <immslam/math/random_samples.h>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <cmath>
#include <numeric>
#include <random>
#include <set>
#include <sstream>

using namespace immslam;
using namespace immslam::eval;

namespace
{
using math::randomQuat;
using math::randomVec3;
TSim3 randomSim3(std::mt19937& rng, bool withScale)
{
  std::uniform_real_distribution<double> u(0.2, 5.0);
  return TSim3{withScale ? u(rng) : 1.0, math::quatToRotation(randomQuat(rng)), randomVec3(rng, 3.0)};
}
/** A smooth non-planar camera path at 30 Hz with rotating orientation. */
core::TTrajectory makeTrajectory(size_t n, double t0 = 100.0, double period = 1.0 / 30)
{
  core::TTrajectory tr;
  for (size_t k = 0; k < n; ++k)
  {
    const double s = static_cast<double>(k) * 0.05;
    core::TStampedPose p;
    p.timestamp = t0 + static_cast<double>(k) * period;
    p.p_W_C = Vec3(std::cos(s) * 2, std::sin(1.3 * s), 0.3 * s + 0.2 * std::sin(3 * s));
    p.q_W_C = math::quatFromRotationVector(Vec3(0.1 * std::sin(s), s, 0.05 * s));
    tr.push_back(p);
  }
  return tr;
}
void expectProperRotation(const Mat3& R, double tol = 1e-12)
{
  EXPECT_TRUE(R.allFinite());
  EXPECT_LT((R.transpose() * R - Mat3::Identity()).norm(), tol);
  EXPECT_NEAR(R.determinant(), 1.0, tol);
}
}  // namespace

// ---------------------------------------------------------------------------------------------
// Association
namespace
{
/** Reference: TUM associate.py's exhaustive greedy (all pairs within maxDt, closest first). */
std::set<std::pair<size_t, size_t>> bruteForceAssociate(const core::TTrajectory& a, const core::TTrajectory& b, double maxDt)
{
  std::vector<std::tuple<double, size_t, size_t>> c;
  for (size_t i = 0; i < a.size(); ++i)
    for (size_t j = 0; j < b.size(); ++j)
      if (std::abs(a[i].timestamp - b[j].timestamp) <= maxDt)
        c.emplace_back(std::abs(a[i].timestamp - b[j].timestamp), i, j);
  std::sort(c.begin(), c.end());
  std::set<size_t> ua, ub;
  std::set<std::pair<size_t, size_t>> out;
  for (const auto& [dt, i, j] : c)
    if (!ua.count(i) && !ub.count(j))
    {
      ua.insert(i);
      ub.insert(j);
      out.emplace(i, j);
    }
  return out;
}
}  // namespace

TEST(Associate, JitterAndMissingEntries)
{
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.004, 0.004);
  const core::TTrajectory gtFull = makeTrajectory(300);
  // Estimate: every frame except multiples of 7, jittered by up to 4 ms, in shuffled order.
  core::TTrajectory est;
  std::vector<size_t> truthGt;  // gt index each estimate pose belongs to
  for (size_t k = 0; k < gtFull.size(); ++k)
  {
    if (k % 7 == 0) continue;
    core::TStampedPose p = gtFull[k];
    p.timestamp += jitter(rng);
    est.push_back(p);
    truthGt.push_back(k);
  }
  // Ground truth missing every 11th pose.
  core::TTrajectory gt;
  std::vector<size_t> gtOrig;
  for (size_t k = 0; k < gtFull.size(); ++k)
    if (k % 11 != 5)
    {
      gt.push_back(gtFull[k]);
      gtOrig.push_back(k);
    }
  const auto pairs = associateByTimestamp(est, gt, 0.01);
  size_t expected = 0;
  for (size_t k = 0; k < gtFull.size(); ++k) expected += (k % 7 != 0 && k % 11 != 5);
  EXPECT_EQ(pairs.size(), expected);
  std::set<size_t> usedA, usedB;
  for (size_t n = 0; n < pairs.size(); ++n)
  {
    const auto [i, j] = pairs[n];
    EXPECT_EQ(gtOrig[j], truthGt[i]);
    EXPECT_TRUE(usedA.insert(i).second);
    EXPECT_TRUE(usedB.insert(j).second);
    if (n > 0)
    {
      EXPECT_LT(est[pairs[n - 1].first].timestamp, est[i].timestamp);  // time order
    }
  }
  // Shuffled input gives the same pairs.
  std::vector<size_t> perm(est.size());
  std::iota(perm.begin(), perm.end(), 0);
  std::shuffle(perm.begin(), perm.end(), rng);
  core::TTrajectory shuffled;
  for (size_t k : perm) shuffled.push_back(est[k]);
  const auto pairs2 = associateByTimestamp(shuffled, gt, 0.01);
  ASSERT_EQ(pairs2.size(), pairs.size());
  for (size_t n = 0; n < pairs.size(); ++n)
  {
    EXPECT_EQ(perm[pairs2[n].first], pairs[n].first);
    EXPECT_EQ(pairs2[n].second, pairs[n].second);
  }
  // A tighter window loses the poses jittered by more than 2 ms.
  EXPECT_LT(associateByTimestamp(est, gt, 0.002).size(), pairs.size());
  EXPECT_TRUE(associateByTimestamp(est, core::TTrajectory{}, 0.01).empty());
  EXPECT_THROW(associateByTimestamp(est, gt, -1.0), std::invalid_argument);
}

TEST(Associate, EqualsExhaustiveGreedyWhenWindowBelowHalfPeriod)
{
  std::mt19937 rng(11);
  for (int trial = 0; trial < 30; ++trial)
  {
    std::uniform_real_distribution<double> u(0, 10);
    // b sampled every 0.05 s with gaps; a random times (dense, may cluster). maxDt = 0.02 < 0.025.
    core::TTrajectory a, b;
    for (int k = 0; k < 200; ++k)
      if (rng() % 4) b.push_back(core::TStampedPose{0.05 * k, Vec3::Zero(), Vec4(1, 0, 0, 0)});
    for (int k = 0; k < 150; ++k) a.push_back(core::TStampedPose{u(rng), Vec3::Zero(), Vec4(1, 0, 0, 0)});
    const auto p = associateByTimestamp(a, b, 0.02);
    const std::set<std::pair<size_t, size_t>> got(p.begin(), p.end());
    EXPECT_EQ(got, bruteForceAssociate(a, b, 0.02)) << "trial " << trial;
    // Sparse first argument, dense second.
    const auto q = associateByTimestamp(b, a, 0.02);
    const std::set<std::pair<size_t, size_t>> got2(q.begin(), q.end());
    EXPECT_EQ(got2, bruteForceAssociate(b, a, 0.02)) << "trial " << trial;
  }
}

// ---------------------------------------------------------------------------------------------
// Umeyama
TEST(Umeyama, RecoversSim3AndSE3ExactlyWithoutNoise)
{
  std::mt19937 rng(3);
  for (bool withScale : {true, false})
    for (int trial = 0; trial < 20; ++trial)
    {
      const TSim3 T = randomSim3(rng, withScale);
      std::vector<Vec3> src, dst;
      for (int i = 0; i < 30; ++i)
      {
        src.push_back(randomVec3(rng, 2.0) + Vec3(5, -3, 1));
        dst.push_back(T.transform(src.back()));
      }
      int rank = -1;
      const TSim3 A = alignUmeyama(src, dst, withScale, &rank);
      EXPECT_EQ(rank, 3);
      expectProperRotation(A.R);
      EXPECT_NEAR(A.s, T.s, 1e-12 * T.s);
      EXPECT_LT((A.R - T.R).norm(), 1e-12);
      EXPECT_LT((A.t - T.t).norm(), 1e-10);
    }
}

TEST(Umeyama, ApproximatelyRecoversWithNoise)
{
  std::mt19937 rng(4);
  for (int trial = 0; trial < 10; ++trial)
  {
    const TSim3 T = randomSim3(rng, true);
    std::vector<Vec3> src, dst;
    for (int i = 0; i < 2000; ++i)
    {
      src.push_back(randomVec3(rng, 3.0));
      dst.push_back(T.transform(src.back()) + randomVec3(rng, 0.01 * T.s));
    }
    const TSim3 A = alignUmeyama(src, dst, true);
    expectProperRotation(A.R);
    EXPECT_NEAR(A.s / T.s, 1.0, 1e-3);
    EXPECT_LT((A.R - T.R).norm(), 1e-3);
    EXPECT_LT((A.t - T.t).norm(), 3e-3 * T.s);
    // The least-squares solution is at least as good as the true transform on the data.
    double costA = 0, costT = 0;
    for (size_t i = 0; i < src.size(); ++i)
    {
      costA += (dst[i] - A.transform(src[i])).squaredNorm();
      costT += (dst[i] - T.transform(src[i])).squaredNorm();
    }
    EXPECT_LE(costA, costT * (1 + 1e-12));
  }
}

TEST(Umeyama, MatchesEigenUmeyamaOnNoisyData)
{
  // Eigen::umeyama is an independent implementation of the same estimator.
  std::mt19937 rng(17);
  for (bool withScale : {true, false})
    for (int trial = 0; trial < 10; ++trial)
    {
      const TSim3 T = randomSim3(rng, withScale);
      const int n = 15;
      std::vector<Vec3> src, dst;
      Eigen::Matrix3Xd S(3, n), D(3, n);
      for (int i = 0; i < n; ++i)
      {
        src.push_back(randomVec3(rng));
        dst.push_back(T.transform(src.back()) + randomVec3(rng, 0.3));
        S.col(i) = src.back();
        D.col(i) = dst.back();
      }
      const TSim3 A = alignUmeyama(src, dst, withScale);
      const Mat4 E = Eigen::umeyama(S, D, withScale);
      EXPECT_LT((A.s * A.R - E.topLeftCorner<3, 3>()).norm(), 1e-10);
      EXPECT_LT((A.t - E.topRightCorner<3, 1>()).norm(), 1e-10);
    }
}

TEST(Umeyama, ReflectedDataGivesProperRotation)
{
  std::mt19937 rng(5);
  std::vector<Vec3> src, dst;
  for (int i = 0; i < 20; ++i)
  {
    src.push_back(randomVec3(rng));
    dst.push_back(Vec3(-src.back().x(), src.back().y(), src.back().z()));  // a mirror image
  }
  const TSim3 A = alignUmeyama(src, dst, true);
  expectProperRotation(A.R);
  EXPECT_TRUE(std::isfinite(A.s));
  EXPECT_GT(A.s, 0);
}

TEST(Umeyama, PlanarPointsAreExact)
{
  std::mt19937 rng(6);
  const TSim3 T = randomSim3(rng, true);
  std::vector<Vec3> src, dst;
  for (int i = 0; i < 10; ++i)
  {
    src.push_back(Vec3(rng() % 7, rng() % 5, 2.0));  // z = const
    dst.push_back(T.transform(src.back()));
  }
  int rank = -1;
  const TSim3 A = alignUmeyama(src, dst, true, &rank);
  EXPECT_EQ(rank, 2);
  EXPECT_NEAR(A.s, T.s, 1e-12 * T.s);
  EXPECT_LT((A.R - T.R).norm(), 1e-11);
  EXPECT_LT((A.t - T.t).norm(), 1e-10);
}

TEST(Umeyama, DegenerateInputsGiveNoNaN)
{
  std::mt19937 rng(8);
  const TSim3 T = randomSim3(rng, true);
  int rank = -1;
  // No points: identity.
  TSim3 A = alignUmeyama({}, {}, true, &rank);
  EXPECT_EQ(rank, 0);
  EXPECT_EQ(A.s, 1.0);
  EXPECT_EQ(A.R, Mat3::Identity());
  EXPECT_EQ(A.t, Vec3::Zero());
  // One point and identical points: translation only.
  for (int n : {1, 5})
  {
    const std::vector<Vec3> src(n, Vec3(0.1, 0.2, 0.3));
    const std::vector<Vec3> dst(n, T.transform(src[0]));
    A = alignUmeyama(src, dst, true, &rank);
    EXPECT_EQ(rank, 0);
    EXPECT_EQ(A.s, 1.0);
    EXPECT_EQ(A.R, Mat3::Identity());
    EXPECT_LT((A.transform(src[0]) - dst[0]).norm(), 1e-12);
  }
  // Identical dst with spread src: translation only onto the centroid.
  {
    const std::vector<Vec3> src = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
    const std::vector<Vec3> dst(3, Vec3(4, 5, 6));
    A = alignUmeyama(src, dst, true, &rank);
    EXPECT_EQ(rank, 0);
    EXPECT_EQ(A.s, 1.0);
    EXPECT_TRUE(A.t.allFinite());
  }
  // Two points and collinear points: exact fit, smallest rotation, proper and finite.
  for (int n : {2, 6})
  {
    std::vector<Vec3> src, dst;
    const Vec3 dir = randomVec3(rng).normalized();
    for (int i = 0; i < n; ++i)
    {
      src.push_back(Vec3(1, 2, 3) + (0.7 * i - 1.0) * dir);
      dst.push_back(T.transform(src.back()));
    }
    for (bool withScale : {true, false})
    {
      A = alignUmeyama(src, dst, withScale, &rank);
      EXPECT_EQ(rank, 1);
      expectProperRotation(A.R);
      EXPECT_TRUE(A.t.allFinite());
      if (withScale)
      {
        EXPECT_NEAR(A.s, T.s, 1e-10 * T.s);
        for (int i = 0; i < n; ++i) EXPECT_LT((A.transform(src[i]) - dst[i]).norm(), 1e-9);
      }
      // Smallest rotation: its axis is perpendicular to both line directions.
      const Vec3 u = (dst.back() - dst.front()).normalized();
      EXPECT_LT((A.R * dir - u).norm(), 1e-9);
      const Vec3 axis = math::quatToRotationVector(math::fromEigen(Eigen::Quaterniond(A.R)));
      EXPECT_LT(std::abs(axis.dot(dir)), 1e-9);
    }
  }
  EXPECT_THROW(alignUmeyama({Vec3::Zero()}, {}, true), std::invalid_argument);
  EXPECT_THROW(alignUmeyama({Vec3(NAN, 0, 0)}, {Vec3::Zero()}, true), std::invalid_argument);
}

TEST(Sim3, InverseAndComposition)
{
  std::mt19937 rng(9);
  const TSim3 A = randomSim3(rng, true), B = randomSim3(rng, true);
  const Vec3 x = randomVec3(rng);
  EXPECT_LT(((A * B).transform(x) - A.transform(B.transform(x))).norm(), 1e-12);
  EXPECT_LT((A.inverse().transform(A.transform(x)) - x).norm(), 1e-12);
}

// ---------------------------------------------------------------------------------------------
// ATE and RPE
TEST(Ate, Sim3TransformedCopyHasZeroErrorAndRightScale)
{
  std::mt19937 rng(10);
  const core::TTrajectory gt = makeTrajectory(200);
  const TSim3 T = randomSim3(rng, true);
  const core::TTrajectory est = applySim3(T, gt);  // est = T(gt): alignment must be T^-1
  const TAteResult r = computeAte(est, gt);
  EXPECT_EQ(r.nPairs, gt.size());
  EXPECT_LT(r.rmse, 1e-9);
  EXPECT_LT(r.max, 1e-9);
  EXPECT_LT(r.rotationRmseDeg, 1e-6);
  EXPECT_NEAR(r.scale, 1.0 / T.s, 1e-10);
  EXPECT_LT((r.R - T.R.transpose()).norm(), 1e-10);
  EXPECT_EQ(r.alignmentRank, 3);
  ASSERT_EQ(r.errors.size(), gt.size());
  EXPECT_EQ(r.errors[17].tGt, gt[17].timestamp);
  // The reported alignment maps est onto gt.
  const core::TTrajectory aligned = applySim3(r.sim3(), est);
  EXPECT_LT((aligned[50].p_W_C - gt[50].p_W_C).norm(), 1e-9);
  // SE(3) cannot absorb the scale; no alignment is worse still.
  const TAteResult se3 = computeAte(est, gt, EAlignment::SE3);
  EXPECT_EQ(se3.scale, 1.0);
  EXPECT_GT(se3.rmse, 1e-3);
  const TAteResult none = computeAte(est, gt, EAlignment::None);
  EXPECT_GE(none.rmse, se3.rmse);
  EXPECT_EQ(ateOverTime(est, gt).size(), gt.size());
}

TEST(Ate, SE3CopyAndPathLengthExtent)
{
  // A square of side 2 in the z = 0 plane, 4 samples per side; est rigidly moved and noisy.
  core::TTrajectory gt;
  const Vec3 corners[5] = {{0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 0}, {0, 0, 0}};
  double t = 0;
  for (int side = 0; side < 4; ++side)
    for (int k = 0; k < 4; ++k)
      gt.push_back(core::TStampedPose{t++, corners[side] + 0.25 * k * (corners[side + 1] - corners[side]),
                                Vec4(1, 0, 0, 0)});
  std::mt19937 rng(12);
  const TSim3 T = randomSim3(rng, false);
  const TAteResult r = computeAte(applySim3(T, gt), gt, EAlignment::SE3, 0.001);
  EXPECT_EQ(r.nPairs, 16u);
  EXPECT_LT(r.rmse, 1e-9);
  EXPECT_EQ(r.alignmentRank, 2);
  EXPECT_NEAR(r.pathLength, 7.5, 1e-12);  // 15 steps of 0.5
  EXPECT_NEAR(r.extent, std::sqrt(8.0), 1e-12);
  EXPECT_NEAR(r.rmseOverPath, r.rmse / 7.5, 1e-15);

  // Known errors with no alignment: est offset by +1 in z on half the poses.
  core::TTrajectory est = gt;
  for (size_t k = 0; k < est.size(); k += 2) est[k].p_W_C.z() += 1.0;
  const TAteResult n = computeAte(est, gt, EAlignment::None, 0.001);
  EXPECT_NEAR(n.rmse, std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(n.mean, 0.5, 1e-12);
  EXPECT_NEAR(n.median, 0.5, 1e-12);
  EXPECT_NEAR(n.max, 1.0, 1e-12);
  EXPECT_NEAR(n.rmseOverExtent, std::sqrt(0.5) / std::sqrt(8.0), 1e-12);

  EXPECT_THROW(computeAte(est, makeTrajectory(10, 1000.0), EAlignment::Sim3), std::runtime_error);
}

TEST(Rpe, ScaledCopyHasZeroRpeWithSim3AndKnownErrorWithout)
{
  std::mt19937 rng(13);
  const core::TTrajectory gt = makeTrajectory(120);
  const TSim3 T = randomSim3(rng, true);
  const core::TTrajectory est = applySim3(T, gt);
  const TRpeResult r = computeRpe(est, gt, 5);
  EXPECT_EQ(r.nPairs, gt.size() - 5);
  EXPECT_NEAR(r.scale, 1.0 / T.s, 1e-10);
  EXPECT_LT(r.translationMax, 1e-9);
  EXPECT_LT(r.rotationMaxDeg, 1e-6);
  // Without the scale, the relative translation error is |s - 1| |dp_gt|.
  const TRpeResult u = computeRpe(est, gt, 1, EAlignment::SE3);
  const double step = (gt[1].p_W_C - gt[0].p_W_C).norm();
  EXPECT_NEAR(u.errors[0].translation, std::abs(T.s - 1) * step, 1e-9);
  EXPECT_LT(u.rotationMaxDeg, 1e-6);
  EXPECT_THROW(computeRpe(est, gt, 0), std::invalid_argument);
  EXPECT_THROW(computeRpe(est, gt, 500), std::runtime_error);
}

TEST(Rpe, DirectionErrorIsScaleFreeAndKnown)
{
  // A straight path along x at 0.1 per frame; the estimate drifts its heading by a known angle about
  // z (positions only, orientation identity): every relative translation over delta frames is rotated by
  // that angle, at any scale.
  core::TTrajectory gt, est;
  const double ang = 10.0 * M_PI / 180.0;
  for (int k = 0; k < 50; ++k)
  {
    gt.push_back(core::TStampedPose{k / 30.0, Vec3(0.1 * k, 0, 0), Vec4(1, 0, 0, 0)});
    est.push_back(core::TStampedPose{k / 30.0, 3.0 * Vec3(0.1 * k * std::cos(ang), 0.1 * k * std::sin(ang), 0), Vec4(1, 0, 0, 0)});
  }
  const TRpeResult r = computeRpe(est, gt, 5, EAlignment::SE3);
  EXPECT_EQ(r.nDirections, r.nPairs);
  EXPECT_NEAR(r.directionMedianDeg, 10.0, 1e-9);
  EXPECT_NEAR(r.directionRmseDeg, 10.0, 1e-9);
  for (const auto& e : r.errors) EXPECT_NEAR(e.directionDeg, 10.0, 1e-9);
  // A ground truth that stands still for a while: those motions have no direction.
  core::TTrajectory still = gt, est2 = gt;
  for (int k = 10; k < 20; ++k) still[k].p_W_C = still[10].p_W_C;
  for (int k = 20; k < 50; ++k) still[k].p_W_C.x() -= 1.0;
  est2 = still;
  const TRpeResult s2 = computeRpe(est2, still, 1, EAlignment::SE3);
  EXPECT_EQ(s2.nDirections, s2.nPairs - 10);  // 10 motions within the still part (and none longer)
  EXPECT_LT(s2.directionRmseDeg, 1e-6);
  size_t nan = 0;
  for (const auto& e : s2.errors)
  {
    nan += std::isnan(e.directionDeg) ? 1 : 0;
    EXPECT_EQ(std::isnan(e.scaleRatio), std::isnan(e.directionDeg));
  }
  EXPECT_EQ(nan, 10u);
}

TEST(Rpe, LocalScaleRatioShowsAKnownScaleDrift)
{
  // A straight path along x at 0.1 per frame; the estimate keeps that step for 29 motions, then
  // doubles it (a monocular map whose scale jumps by 2): local scales 1 then 2 without alignment.
  core::TTrajectory gt, est;
  for (int k = 0; k < 60; ++k)
  {
    gt.push_back(core::TStampedPose{k / 30.0, Vec3(0.1 * k, 0, 0), Vec4(1, 0, 0, 0)});
    const double x = k <= 29 ? 0.1 * k : 2.9 + 0.2 * (k - 29);
    est.push_back(core::TStampedPose{k / 30.0, Vec3(x, 0, 0), Vec4(1, 0, 0, 0)});
  }
  const TRpeResult r = computeRpe(est, gt, 1, EAlignment::SE3);
  ASSERT_EQ(r.nPairs, 59u);
  for (size_t k = 0; k < r.errors.size(); ++k) EXPECT_NEAR(r.errors[k].scaleRatio, k < 29 ? 1.0 : 2.0, 1e-9);
  EXPECT_NEAR(r.scaleRatioMedian, 2.0, 1e-9);  // 30 of the 59 motions are doubled
  EXPECT_NEAR(r.scaleRatioP10, 1.0, 1e-9);
  EXPECT_NEAR(r.scaleRatioP90, 2.0, 1e-9);
  EXPECT_NEAR(r.scaleLogRms, std::log(2.0) * std::sqrt(30.0 / 59.0), 1e-9);
  // With Sim3 the overall scale s multiplies every ratio; their quotient stays 2.
  const TRpeResult a = computeRpe(est, gt, 1, EAlignment::Sim3);
  EXPECT_NEAR(a.errors.back().scaleRatio / a.errors.front().scaleRatio, 2.0, 1e-9);
  EXPECT_NEAR(a.errors.front().scaleRatio, a.scale, 1e-9);
  // No drift: every ratio 1, log rms 0.
  const TRpeResult same = computeRpe(gt, gt, 3, EAlignment::SE3);
  EXPECT_NEAR(same.scaleRatioP10, 1.0, 1e-12);
  EXPECT_NEAR(same.scaleRatioP90, 1.0, 1e-12);
  EXPECT_NEAR(same.scaleLogRms, 0.0, 1e-12);
}

// ---------------------------------------------------------------------------------------------
// Consistency
TEST(Nees, KnownValuesAndNonPD)
{
  EXPECT_DOUBLE_EQ(nees(Vec2(1, 2), Mat2(Eigen::Vector2d(1, 4).asDiagonal())), 2.0);
  MatX P(2, 2);
  P << 2, 1, 1, 2;
  EXPECT_NEAR(nees(Vec2(1, 1), P), 2.0 / 3.0, 1e-15);  // P^-1 = [2 -1; -1 2]/3
  P << 1, 2, 2, 1;  // indefinite
  EXPECT_TRUE(std::isinf(nees(Vec2(1, 1), P)));
  EXPECT_TRUE(std::isinf(nees(Vec2(1, 1), MatX::Zero(2, 2))));
  EXPECT_TRUE(std::isinf(nees(Vec2(NAN, 1), MatX::Identity(2, 2))));
  EXPECT_THROW(nees(Vec3(1, 1, 1), MatX::Identity(2, 2)), std::invalid_argument);
}

TEST(Nees, BandMatchesIndependentChi2Values)
{
  // Reference quantiles computed independently (closed-form CDF of an even-dof chi-square,
  // 1 - exp(-x/2) sum_{j<k/2} (x/2)^j / j!, inverted by bisection; dof 1 from the normal table).
  const TChi2Band b = averageNeesBand(6, 25);
  EXPECT_NEAR(b.lower, 4.719380616, 1e-7);  // chi2_150(0.025) / 25 = 117.98452 / 25
  EXPECT_NEAR(b.upper, 7.432017880, 1e-7);  // chi2_150(0.975) / 25 = 185.80045 / 25
  EXPECT_EQ(b.dof, 6);
  EXPECT_EQ(b.nRuns, 25);
  const TChi2Band b2 = averageNeesBand(2, 10);
  EXPECT_NEAR(b2.lower, 0.9590777393, 1e-7);
  EXPECT_NEAR(b2.upper, 3.4169606903, 1e-7);
  const TChi2Band b3 = averageNeesBand(6, 1);
  EXPECT_NEAR(b3.lower, 1.237344246, 1e-7);
  EXPECT_NEAR(b3.upper, 14.44937534, 1e-7);
  const TChi2Band b4 = averageNeesBand(1, 1);
  EXPECT_NEAR(b4.lower, 9.820691e-4, 1e-9);  // (1.959964 * 0.0313...)^2 table value
  EXPECT_NEAR(b4.upper, 5.023886187, 1e-7);  // 1.959963985^2
  const TChi2Band b5 = averageNeesBand(6, 25, 0.99);
  EXPECT_NEAR(b5.lower, 4.365689924, 1e-7);
  EXPECT_NEAR(b5.upper, 7.934408240, 1e-7);
  EXPECT_TRUE(b.contains(6.0));
  EXPECT_FALSE(b.contains(8.0));
  EXPECT_THROW(averageNeesBand(0, 5), std::invalid_argument);
  EXPECT_THROW(averageNeesBand(3, 5, 1.0), std::invalid_argument);
}

TEST(Nees, MonteCarloGaussianSamplesAreConsistent)
{
  std::mt19937 rng(14);
  std::normal_distribution<double> n01;
  const int dof = 6, runs = 25;
  const size_t steps = 2000;
  // A random PD covariance and its Cholesky factor to draw e ~ N(0, P).
  MatX A = MatX::NullaryExpr(dof, dof, [&]() { return n01(rng); });
  const MatX P = A * A.transpose() + 0.5 * MatX::Identity(dof, dof);
  const MatX L = Eigen::LLT<MatX>(P).matrixL();
  CNeesAccumulator acc(dof);
  for (size_t k = 0; k < steps; ++k)
    for (int r = 0; r < runs; ++r)
    {
      const VecX z = VecX::NullaryExpr(dof, [&]() { return n01(rng); });
      acc.add(k, VecX(L * z), P);
    }
  EXPECT_EQ(acc.numSteps(), steps);
  EXPECT_EQ(acc.runsAt(3), static_cast<size_t>(runs));
  // Mean of 50000 chi2_6 values: sd of the mean is sqrt(12 / 50000) = 0.0155.
  EXPECT_NEAR(acc.overallAverage(), dof, 0.06);
  // Fraction of steps inside the 95 % band: sd sqrt(0.95 * 0.05 / 2000) = 0.005.
  const double f = acc.fractionInsideBand(0.95);
  EXPECT_NEAR(f, 0.95, 0.02);
  EXPECT_NEAR(acc.fractionInsideBand(0.99), 0.99, 0.01);
  // An overconfident filter (covariance 4x too small) falls outside.
  CNeesAccumulator bad(dof);
  for (size_t k = 0; k < 200; ++k)
    for (int r = 0; r < runs; ++r)
    {
      const VecX z = VecX::NullaryExpr(dof, [&]() { return n01(rng); });
      bad.add(k, VecX(L * z), MatX(P / 4));
    }
  EXPECT_LT(bad.fractionInsideBand(), 0.05);
  EXPECT_TRUE(std::isnan(CNeesAccumulator(3).fractionInsideBand()));
  EXPECT_TRUE(std::isnan(acc.averageAt(steps + 10)));
}

TEST(PoseError, ConventionJacobianAndNees)
{
  std::mt19937 rng(15);
  const Vec4 qTrue = randomQuat(rng);
  const Vec3 pTrue = randomVec3(rng);
  // A known body-frame rotation error: q_est = q_true Exp(theta).
  const Vec3 theta(0.01, -0.02, 0.03), dp(0.1, 0.2, -0.3);
  const Vec4 qEst = math::quatMultiply(qTrue, math::quatFromRotationVector(theta));
  const Vec6 e = poseError6(pTrue + dp, qEst, pTrue, qTrue);
  EXPECT_LT((e.head<3>() - dp).norm(), 1e-15);
  EXPECT_LT((e.tail<3>() - theta).norm(), 1e-12);
  // Sign of the quaternion does not matter.
  EXPECT_LT((poseError6(pTrue, -qEst, pTrue, qTrue).tail<3>() - theta).norm(), 1e-12);

  // J = dLog(qhat^-1 q)/dq at q = qhat, against a numerical Jacobian.
  Mat34 J;
  MatX P7 = MatX::Identity(7, 7) * 1e-4;
  const Mat6 P6 = poseCovariance6(qEst, P7, &J);
  const MatX Jn = math::numericalJacobian(
      [&](const VecX& q) -> VecX {
        return math::quatToRotationVector(math::quatMultiply(math::quatConjugate(qEst), q));
      },
      VecX(qEst));
  EXPECT_LT((Jn - J).norm(), 1e-8);
  EXPECT_LT((J * qEst).norm(), 1e-14);  // the norm direction is removed
  // An isotropic quaternion covariance s I4 maps to 4 s I3 on the tangent space.
  EXPECT_LT((P6.bottomRightCorner<3, 3>() - 4e-4 * Mat3::Identity()).norm(), 1e-15);
  EXPECT_THROW(poseCovariance6(qEst, MatX::Identity(6, 6)), std::invalid_argument);

  // Monte Carlo: perturbing q additively with covariance Pq gives theta with covariance J Pq J^T,
  // so the pose NEES averages to 6.
  std::normal_distribution<double> n01;
  Eigen::Matrix<double, 7, 7> Prq = Eigen::Matrix<double, 7, 7>::Zero();
  Prq.topLeftCorner<3, 3>() = Vec3(0.01, 0.02, 0.03).asDiagonal();
  Prq.bottomRightCorner<4, 4>() = 1e-4 * (Mat4::Identity() - qEst * qEst.transpose()) + 1e-6 * Mat4::Identity();
  const MatX Lrq = Eigen::LLT<MatX>(MatX(Prq)).matrixL();
  double sum = 0;
  const int N = 20000;
  for (int i = 0; i < N; ++i)
  {
    const VecX z = VecX::NullaryExpr(7, [&]() { return n01(rng); });
    const VecX x = Lrq * z;  // true = estimate - x (estimate error x)
    const Vec3 pT = pTrue - x.head<3>();
    const Vec4 qT = (qEst - x.tail<4>()).normalized();
    sum += poseNees(pTrue, qEst, pT, qT, Prq);
  }
  EXPECT_NEAR(sum / N, 6.0, 0.15);
}

// ---------------------------------------------------------------------------------------------
// Classification and statistics
TEST(ConfusionMatrix, Rates)
{
  TConfusionMatrix m;
  for (int i = 0; i < 90; ++i) m.add(EMotionClass::Static, EMotionClass::Static);
  for (int i = 0; i < 10; ++i) m.add(EMotionClass::Static, EMotionClass::Dynamic);
  for (int i = 0; i < 5; ++i) m.add(EMotionClass::Dynamic, EMotionClass::Static);
  for (int i = 0; i < 15; ++i) m.add(EMotionClass::Dynamic, EMotionClass::Dynamic);
  EXPECT_EQ(m.total(), 120u);
  EXPECT_DOUBLE_EQ(m.movingAsStaticRate(), 0.25);
  EXPECT_DOUBLE_EQ(m.staticAsDynamicRate(), 0.10);
  EXPECT_DOUBLE_EQ(m.accuracy(), 105.0 / 120.0);
  EXPECT_DOUBLE_EQ(m.precision(), 0.6);
  EXPECT_DOUBLE_EQ(m.recall(), 0.75);
  EXPECT_NEAR(m.f1(), 2 * 0.6 * 0.75 / 1.35, 1e-15);
  const std::string s = m.summary();
  EXPECT_NE(s.find("moving->static rate : 25.00 % (5/20)"), std::string::npos) << s;
  EXPECT_NE(s.find("static->dynamic rate: 10.00 % (10/100)"), std::string::npos) << s;
  std::ostringstream os;
  os << m;
  EXPECT_EQ(os.str(), s);
  TConfusionMatrix sum = m;
  sum += m;
  EXPECT_EQ(sum.dynamicAsDynamic, 30u);
  TConfusionMatrix empty;
  EXPECT_TRUE(std::isnan(empty.accuracy()));
  EXPECT_NE(empty.summary().find("n/a"), std::string::npos);
}

TEST(Statistics, AgainstHandComputedValues)
{
  const std::vector<double> v = {3, 1, 4, 1, 5, 9, 2, 6};
  EXPECT_DOUBLE_EQ(mean(v), 31.0 / 8);
  EXPECT_DOUBLE_EQ(median(v), 3.5);
  EXPECT_DOUBLE_EQ(median({7, 1, 3}), 3.0);
  EXPECT_DOUBLE_EQ(rms({3, 4}), std::sqrt(12.5));
  EXPECT_DOUBLE_EQ(percentile(v, 0), 1.0);
  EXPECT_DOUBLE_EQ(percentile(v, 100), 9.0);
  EXPECT_DOUBLE_EQ(percentile(v, 25), 1.75);   // numpy.percentile(v, 25)
  EXPECT_DOUBLE_EQ(percentile(v, 90), 6.9);    // rank 6.3 between 6 and 9
  EXPECT_DOUBLE_EQ(percentile({42}, 37), 42.0);
  EXPECT_DOUBLE_EQ(maxValue(v), 9.0);
  EXPECT_DOUBLE_EQ(minValue(v), 1.0);
  EXPECT_NEAR(stddev({2, 4, 4, 4, 5, 5, 7, 9}), 2.0, 1e-15);
  const TSummaryStats s = summarize(v);
  EXPECT_EQ(s.n, v.size());
  EXPECT_DOUBLE_EQ(s.median, 3.5);
  EXPECT_THROW(mean({}), std::invalid_argument);
  EXPECT_THROW(percentile(v, 101), std::invalid_argument);
}
