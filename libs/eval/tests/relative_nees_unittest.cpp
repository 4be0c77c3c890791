/* Tests: NEES of the filter's relative poses (relative_poses.csv): motions drawn from their stated
 * covariance give 3 and 6 dof on average with ~95 % inside the bounds, an over-confident covariance
 * does not, the map's scale enters the translation, and the reader names the file and line. */
#include <gtest/gtest.h>
#include <immslam/eval/relative_nees.h>
#include <immslam/math/quaternion.h>

#include <Eigen/Cholesky>
#include <filesystem>
#include <fstream>
#include <random>

using namespace immslam;
using namespace immslam::eval;

namespace
{
std::string tempPath(const std::string& name)
{
  return (std::filesystem::path(::testing::TempDir()) / ("immslam_relnees_" + name)).string();
}

/** A ground-truth path and, every frame from 10 on, its motion over 10 frames in a map 4 times smaller,
 * perturbed by a draw from cov (the row states cov x covFactor). */
void makeRows(double covFactor, core::TTrajectory& gt, std::vector<TRelativePoseRow>& rows, unsigned seed)
{
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  gt.clear();
  rows.clear();
  for (int k = 0; k < 400; ++k)
  {
    core::TStampedPose p;
    p.timestamp = k / 30.0;
    p.p_W_C = Vec3(0.01 * k, 0.2 * std::sin(0.05 * k), 0.1 * std::cos(0.03 * k));
    p.q_W_C = math::quatFromRotationVector(Vec3(0.1 * std::sin(0.02 * k), 0.003 * k, 0.05));
    gt.push_back(p);
  }
  constexpr double kScale = 4.0;  // ground-truth units per map unit
  Mat6 A = Mat6::Random();
  const Mat6 C = 1e-6 * (A * A.transpose() + 0.1 * Mat6::Identity());
  const Mat6 L = C.llt().matrixL();
  for (int k = 10; k < 400; ++k)
  {
    const auto& pj = gt[static_cast<std::size_t>(k - 10)];
    const auto& pk = gt[static_cast<std::size_t>(k)];
    Vec6 n;
    for (int i = 0; i < 6; ++i) n[i] = g(rng);
    const Vec6 e = L * n;
    const Vec3 t = math::quatToRotation(pj.q_W_C).transpose() * (pk.p_W_C - pj.p_W_C) / kScale;
    const Vec4 q = math::quatMultiply(math::quatConjugate(pj.q_W_C), pk.q_W_C);
    TRelativePoseRow r;
    r.timestamp = pk.timestamp;
    r.fromTimestamp = pj.timestamp;
    // Estimate = truth minus the error: t = t_hat + dt, R = R_hat Exp(dtheta).
    r.t = t - e.head<3>();
    r.q = math::quatMultiply(q, math::quatFromRotationVector(-e.tail<3>()));
    r.cov = covFactor * C;
    rows.push_back(r);
  }
}
}  // namespace

TEST(RelativeNees, MotionsDrawnFromTheirCovarianceAreConsistent)
{
  core::TTrajectory gt;
  std::vector<TRelativePoseRow> rows;
  makeRows(1.0, gt, rows, 1);
  const auto r = computeRelativeNees(rows, gt, 4.0);
  EXPECT_EQ(r.nUsed, rows.size());
  ASSERT_EQ(r.full.size(), rows.size());
  double mr = 0, mf = 0;
  int inside = 0;
  for (std::size_t i = 0; i < rows.size(); ++i) mr += r.rotation[i] / rows.size(), mf += r.full[i] / rows.size(), inside += r.full[i] <= 12.59;
  EXPECT_NEAR(mr, 3.0, 0.5);
  EXPECT_NEAR(mf, 6.0, 0.7);
  EXPECT_NEAR(static_cast<double>(inside) / rows.size(), 0.95, 0.03);
  // A covariance stated 10 times too small: NEES 10 times larger.
  makeRows(0.1, gt, rows, 1);
  const auto over = computeRelativeNees(rows, gt, 4.0);
  double mo = 0;
  for (double x : over.full) mo += x / over.full.size();
  EXPECT_NEAR(mo / mf, 10.0, 1e-6 * mo);
  // Without the scale only the rotation is tested; with a wrong one the translation fails.
  const auto noScale = computeRelativeNees(rows, gt, 0);
  EXPECT_TRUE(noScale.full.empty());
  EXPECT_EQ(noScale.rotation, over.rotation);
  makeRows(1.0, gt, rows, 2);
  const auto wrong = computeRelativeNees(rows, gt, 2.0);
  double mw = 0;
  for (double x : wrong.full) mw += x / wrong.full.size();
  EXPECT_GT(mw, 20.0);
  EXPECT_NE(wrong.summary().find("full pose"), std::string::npos);
}

TEST(RelativeNees, TheReaderNamesTheFileAndLine)
{
  std::string head = "timestamp,from_timestamp,tx,ty,tz,qx,qy,qz,qw";
  std::string row = "1,0.5,0,0,0,0,0,0,1";
  for (int i = 0; i < 6; ++i)
    for (int j = i; j < 6; ++j) head += ",c" + std::to_string(i) + std::to_string(j), row += i == j ? ",1" : ",0";
  const std::string good = tempPath("good.csv"), bad = tempPath("bad.csv"), wrongHead = tempPath("head.csv");
  std::ofstream(good) << head << "\n" << row << "\n";
  std::ofstream(bad) << head << "\n" << row << "\n" << row.substr(0, row.size() - 2) << "\n";
  std::ofstream(wrongHead) << "timestamp,tx\n";
  const auto rows = readRelativePosesCsv(good);
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].cov, Mat6::Identity());
  EXPECT_EQ(rows[0].fromTimestamp, 0.5);
  try
  {
    readRelativePosesCsv(bad);
    FAIL();
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find(bad + ":3"), std::string::npos) << e.what();
  }
  EXPECT_THROW(readRelativePosesCsv(wrongHead), std::runtime_error);
  EXPECT_THROW(readRelativePosesCsv(tempPath("missing.csv")), std::runtime_error);
}
