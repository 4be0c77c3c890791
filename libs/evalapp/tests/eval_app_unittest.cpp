/* Tests: the ATE report of slam-eval (`slam-eval ate`, runEvalApp) run in process: report, JSON,
 * exit codes of bad usage and bad input. */
#include <gtest/gtest.h>
#include <immslam/core/TTrajectory.h>
#include <immslam/eval/alignment.h>
#include <immslam/evalapp/eval_app.h>
#include <immslam/math/quaternion.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

using namespace immslam;
using namespace immslam::evalapp;

namespace
{
/** A smooth non-planar camera path at 30 Hz. */
core::TTrajectory makeTrajectory(std::size_t n)
{
  core::TTrajectory tr;
  for (std::size_t k = 0; k < n; ++k)
  {
    const double s = static_cast<double>(k) * 0.05;
    core::TStampedPose p;
    p.timestamp = 100.0 + static_cast<double>(k) / 30;
    p.p_W_C = Vec3(std::cos(s) * 2, std::sin(1.3 * s), 0.3 * s + 0.2 * std::sin(3 * s));
    p.q_W_C = math::quatFromRotationVector(Vec3(0.1 * std::sin(s), s, 0.05 * s));
    tr.push_back(p);
  }
  return tr;
}
/** The trajectory moved by a fixed similarity (scale 2.5, a rotation, a shift). */
core::TTrajectory moved(const core::TTrajectory& t)
{
  const Vec4 dq = math::quatFromRotationVector(Vec3(0.3, -0.5, 1.1));
  const eval::TSim3 S{2.5, math::quatToRotation(dq), Vec3(1, -2, 0.5)};
  core::TTrajectory out = t;
  for (auto& p : out)
  {
    p.p_W_C = S.transform(p.p_W_C);
    p.q_W_C = math::quatMultiply(dq, p.q_W_C);
  }
  return out;
}
std::string tempPath(const std::string& name)
{
  return (std::filesystem::path(::testing::TempDir()) / ("immslam_evalapp_" + name)).string();
}
void writeText(const std::string& path, const std::string& text)
{
  std::ofstream f(path);
  f << text;
}
}  // namespace

// ---------------------------------------------------------------------------------------------
// The ATE report (slam-eval ate, formerly imm-eval), in process.
TEST(EvalApp, ExitCodesAndReport)
{
  const core::TTrajectory gt = makeTrajectory(100);
  const core::TTrajectory est = moved(gt);
  const std::string g = tempPath("app_gt.txt"), e = tempPath("app_est.txt"), bad = tempPath("app_bad.txt");
  core::writeTumTrajectory(gt, g);
  core::writeTumTrajectory(est, e);
  writeText(bad, "1 2 3\n");
  const auto run = [](std::vector<std::string> args, std::string* out = nullptr, std::string* err = nullptr) {
    args.insert(args.begin(), "slam-eval ate");
    std::ostringstream o, r;
    const int rc = runEvalApp(args, o, r);
    if (out) *out = o.str();
    if (err) *err = r.str();
    return rc;
  };
  std::string out, err;
  EXPECT_EQ(run({e, g}, &out), 0);
  EXPECT_NE(out.find("pairs                 : 100"), std::string::npos) << out;
  EXPECT_NE(out.find("ATE / extent"), std::string::npos);
  EXPECT_EQ(run({e, g, "--json", "--se3", "--max-dt", "0.02"}, &out), 0);
  EXPECT_NE(out.find("\"alignment\": \"SE3\""), std::string::npos) << out;
  EXPECT_NE(out.find("\"n_pairs\": 100,"), std::string::npos) << out;
  EXPECT_EQ(run({"--help"}, &out), 0);
  EXPECT_NE(out.find("Usage"), std::string::npos);
  EXPECT_EQ(run({e}), 2);
  EXPECT_EQ(run({e, g, "--max-dt"}), 2);
  EXPECT_EQ(run({e, g, "--max-dt", "abc"}), 2);
  EXPECT_EQ(run({e, g, "--bogus"}), 2);
  EXPECT_EQ(run({e, bad}, nullptr, &err), 1);
  EXPECT_NE(err.find(bad + ":1"), std::string::npos) << err;
  EXPECT_EQ(run({tempPath("nope.txt"), g}, nullptr, &err), 1);
  EXPECT_NE(err.find("nope.txt"), std::string::npos) << err;
}

// --rpe-csv: every relative motion's errors, one row each, where along the run they are.
TEST(EvalApp, RpeCsvHasARowPerRelativeMotionAndMarksTheFramesThatWentWrong)
{
  const core::TTrajectory gt = makeTrajectory(100);
  core::TTrajectory est = moved(gt);
  // The estimate turned by 2 degrees (about the world's z) from pose 60 on: only the motion 59 -> 60
  // (delta 1) has a rotation error.
  const Vec4 dq = math::quatFromRotationVector(Vec3(0, 0, 2 * M_PI / 180));
  for (std::size_t k = 60; k < est.size(); ++k) est[k].q_W_C = math::quatMultiply(dq, est[k].q_W_C);
  const std::string g = tempPath("csv_gt.txt"), e = tempPath("csv_est.txt"), csv = tempPath("rpe.csv");
  core::writeTumTrajectory(gt, g);
  core::writeTumTrajectory(est, e);
  std::filesystem::remove(csv);
  const auto run = [](std::vector<std::string> args, std::string* err = nullptr) {
    args.insert(args.begin(), "slam-eval ate");
    std::ostringstream o, r;
    const int rc = runEvalApp(args, o, r);
    if (err) *err = r.str();
    return rc;
  };
  ASSERT_EQ(run({e, g, "--rpe", "1", "--rpe-csv", csv}), 0);
  std::ifstream f(csv);
  std::string line;
  ASSERT_TRUE(std::getline(f, line));
  EXPECT_EQ(line, "t_start,t_end,translation_error,rotation_error_deg,direction_error_deg,local_scale");
  int rows = 0, wrong = 0;
  while (std::getline(f, line))
  {
    ++rows;
    std::vector<double> v;
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) v.push_back(std::stod(c));
    ASSERT_EQ(v.size(), 6u) << line;
    EXPECT_NEAR(v[1] - v[0], 1.0 / 30, 1e-6) << line;
    if (v[3] > 1)
    {
      ++wrong;
      EXPECT_NEAR(v[3], 2.0, 1e-6) << line;
      EXPECT_NEAR(v[0], 100.0 + 59.0 / 30, 1e-6) << line;
    }
    else
      EXPECT_LT(v[3], 1e-6) << line;
  }
  EXPECT_EQ(rows, 99);
  EXPECT_EQ(wrong, 1);
  // Bad use and a file that cannot be written: exit codes 2 and 1, the file named.
  EXPECT_EQ(run({e, g, "--rpe-csv", csv}), 2);
  EXPECT_EQ(run({e, g, "--rpe", "1", "--rpe-csv"}), 2);
  std::string err;
  const std::string nowhere = tempPath("no_such_dir/rpe.csv");
  EXPECT_EQ(run({e, g, "--rpe", "1", "--rpe-csv", nowhere}, &err), 1);
  EXPECT_NE(err.find(nowhere), std::string::npos) << err;
}
