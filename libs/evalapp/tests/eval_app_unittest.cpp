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
