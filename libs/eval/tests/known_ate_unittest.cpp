/* Tests: ATE with exactly known answers (issue 2, "Done when"): a trajectory against itself is 0;
 * a copy displaced per pose by d_i (zero mean, no cross-correlation with the positions, RMS 0.01)
 * and then moved by a random similarity has, after alignment,
 *  - SE(3) (rigid copy): ATE = RMS(d) = 0.01 exactly (the alignment recovers the rigid motion);
 *  - Sim(3): ATE = sqrt(a b / (a + b)) with a = mean |g_i - mean g|^2 and b = mean |d_i|^2:
 *    the cross-covariance is that of the ground truth itself (rotation exact), but the displaced
 *    copy is more spread, so the best scale shrinks it by s = a / (a + b), which trades part of the
 *    displacement against a scale error: residuals (1 - s)(g_i - mean g) - s d_i. */
#include <gtest/gtest.h>
#include <immslam/core/TTrajectory.h>
#include <immslam/eval/ate.h>
#include <immslam/math/quaternion.h>

#include <Eigen/Dense>
#include <cmath>
#include <filesystem>
#include <random>

using namespace immslam;
using namespace immslam::eval;

namespace
{
/** A hand-held-like path at 30 Hz (6 s): wobbling forward motion with turning orientation. */
core::TTrajectory handheldPath()
{
  core::TTrajectory tr;
  for (int k = 0; k < 180; ++k)
  {
    const double t = k / 30.0;
    core::TStampedPose p;
    p.timestamp = 1000.0 + t;
    p.p_W_C = Vec3(0.4 * std::sin(0.9 * t) + 0.05 * std::sin(7 * t), 0.1 * std::sin(1.7 * t) + 0.03 * std::cos(5 * t),
                   0.25 * t + 0.04 * std::sin(3 * t));
    p.q_W_C = math::quatFromRotationVector(Vec3(0.05 * std::sin(2 * t), 0.3 * std::sin(0.8 * t), 0.02 * t));
    tr.push_back(p);
  }
  return tr;
}

/** Per-pose displacements with zero mean and zero cross-correlation with the positions
 * (sum_i (g_i - mean g) d_i^T = 0), scaled to the given RMS: random vectors minus their least-squares
 * fit by an affine function of the positions. */
std::vector<Vec3> orthogonalDisplacements(const core::TTrajectory& gt, double rms, unsigned seed)
{
  const auto n = static_cast<Eigen::Index>(gt.size());
  Eigen::MatrixXd G(n, 4), D(n, 3);
  std::mt19937 rng(seed);
  std::normal_distribution<double> nd;
  for (Eigen::Index i = 0; i < n; ++i)
  {
    G.row(i) << 1.0, gt[static_cast<size_t>(i)].p_W_C.transpose();
    D.row(i) << nd(rng), nd(rng), nd(rng);
  }
  const Eigen::MatrixXd X = G.colPivHouseholderQr().solve(D);
  D -= G * X;
  D *= rms / std::sqrt(D.rowwise().squaredNorm().mean());
  std::vector<Vec3> d;
  for (Eigen::Index i = 0; i < n; ++i) d.emplace_back(D.row(i).transpose());
  return d;
}

TSim3 randomSim3(std::mt19937& rng, bool withScale)
{
  std::normal_distribution<double> n;
  const Vec4 q = Vec4(n(rng), n(rng), n(rng), n(rng)).normalized();
  return TSim3{withScale ? 3.7 : 1.0, math::quatToRotation(q), Vec3(n(rng), n(rng), n(rng)) * 5};
}
}  // namespace

TEST(KnownAte, TrajectoryAgainstItselfIsZero)
{
  const core::TTrajectory gt = handheldPath();
  for (const EAlignment a : {EAlignment::Sim3, EAlignment::SE3, EAlignment::None})
  {
    const TAteResult r = computeAte(gt, gt, a);
    EXPECT_EQ(r.nPairs, gt.size());
    EXPECT_LT(r.rmse, 1e-12) << alignmentName(a);
    EXPECT_LT(r.rotationRmseDeg, 1e-6) << alignmentName(a);
    EXPECT_NEAR(r.scale, 1.0, 1e-12);
  }
}

TEST(KnownAte, PerturbedCopyHasTheKnownError)
{
  const core::TTrajectory gt = handheldPath();
  const std::vector<Vec3> d = orthogonalDisplacements(gt, 0.01, 5);
  // Check the construction: zero mean, zero cross-correlation, RMS 0.01.
  Vec3 mu = Vec3::Zero(), md = Vec3::Zero();
  for (size_t i = 0; i < gt.size(); ++i) mu += gt[i].p_W_C / double(gt.size()), md += d[i] / double(gt.size());
  Mat3 cross = Mat3::Zero();
  double a = 0, b = 0;
  for (size_t i = 0; i < gt.size(); ++i)
  {
    cross += (gt[i].p_W_C - mu) * d[i].transpose();
    a += (gt[i].p_W_C - mu).squaredNorm() / double(gt.size());
    b += d[i].squaredNorm() / double(gt.size());
  }
  ASSERT_LT(md.norm(), 1e-15);
  ASSERT_LT(cross.norm(), 1e-12);
  ASSERT_NEAR(std::sqrt(b), 0.01, 1e-15);

  core::TTrajectory displaced = gt;
  for (size_t i = 0; i < gt.size(); ++i) displaced[i].p_W_C += d[i];
  std::mt19937 rng(7);
  const TSim3 T = randomSim3(rng, true), Tr = randomSim3(rng, false);

  // SE(3): a rigidly moved displaced copy.
  const TAteResult se3 = computeAte(applySim3(Tr, displaced), gt, EAlignment::SE3);
  EXPECT_NEAR(se3.rmse, 0.01, 1e-12);
  EXPECT_LT(se3.rotationRmseDeg, 1e-6);
  EXPECT_LT((se3.R - Tr.R.transpose()).norm(), 1e-10);
  // No alignment on the displaced copy itself: also RMS(d).
  EXPECT_NEAR(computeAte(displaced, gt, EAlignment::None).rmse, 0.01, 1e-15);

  // Sim(3): a displaced copy moved by a similarity of scale 3.7.
  const TAteResult sim3 = computeAte(applySim3(T, displaced), gt, EAlignment::Sim3);
  const double expected = std::sqrt(a * b / (a + b));
  EXPECT_NEAR(sim3.rmse, expected, 1e-12);
  EXPECT_NEAR(sim3.scale, a / (a + b) / T.s, 1e-12);
  EXPECT_LT((sim3.R - T.R.transpose()).norm(), 1e-10);
  EXPECT_LT(sim3.rotationRmseDeg, 1e-6);
  EXPECT_NEAR(sim3.rmseOverPath, expected / sim3.pathLength, 1e-15);
  std::printf("[ known ATE ] %zu poses, path %.4f, a = %.6f, b = %.3g: self 0; SE3 %.9f (expected 0.01); "
              "Sim3 %.9f (expected %.9f = %.4f %% of the path)\n",
              gt.size(), sim3.pathLength, a, b, se3.rmse, sim3.rmse, expected, 100 * expected / sim3.pathLength);

  // Through TUM files (6-decimal timestamps, shortest round-trip numbers): same figures.
  const auto dir = std::filesystem::path(::testing::TempDir());
  const std::string g = (dir / "immslam_known_ate_gt.txt").string(), e = (dir / "immslam_known_ate_est.txt").string();
  core::writeTumTrajectory(gt, g);
  core::writeTumTrajectory(applySim3(T, displaced), e);
  EXPECT_NEAR(computeAte(core::readTumTrajectory(e), core::readTumTrajectory(g)).rmse, expected, 1e-10);
}
