/* Tests: runSlamEvalApp in process: subcommand dispatch, the old imm-eval form, usage errors (2)
 * and input errors (1). The program itself is run on small files by apps/slam-eval's test. */
#include <gtest/gtest.h>
#include <immslam/eval/TTrajectory.h>
#include <immslam/eval/slam_eval_app.h>

#include <filesystem>
#include <fstream>
#include <sstream>

using namespace immslam;
using namespace immslam::eval;

namespace
{
std::string tempPath(const std::string& name)
{
  return (std::filesystem::path(::testing::TempDir()) / ("immslam_sleapp_" + name)).string();
}
void writeText(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

int run(std::vector<std::string> args, std::string* out = nullptr, std::string* err = nullptr)
{
  args.insert(args.begin(), "slam-eval");
  std::ostringstream o, e;
  const int rc = runSlamEvalApp(args, o, e);
  if (out) *out = o.str();
  if (err) *err = e.str();
  return rc;
}
}  // namespace

TEST(SlamEvalApp, DispatchOldFormAndUsage)
{
  TTrajectory gt;
  for (int k = 0; k < 20; ++k)
    gt.push_back(TStampedPose{k / 30.0, Vec3(k, (k * k) % 5, (3 * k) % 4), Vec4(1, 0, 0, 0)});
  const std::string g = tempPath("gt.txt");
  writeTumTrajectory(gt, g);

  std::string out, outOld, err;
  EXPECT_EQ(run({"--help"}, &out), 0);
  for (const char* c : {"ate", "segmentation", "classification", "nis"}) EXPECT_NE(out.find(c), std::string::npos) << c;
  EXPECT_EQ(run({}, nullptr, &err), 2);
  EXPECT_NE(err.find("no command"), std::string::npos);

  EXPECT_EQ(run({"ate", g, g}, &out), 0);
  EXPECT_EQ(run({g, g}, &outOld), 0);
  EXPECT_EQ(out, outOld);
  EXPECT_NE(out.find("pairs                 : 20"), std::string::npos) << out;
  EXPECT_EQ(run({"ate", "--help"}, &out), 0);
  EXPECT_NE(out.find("Usage: slam-eval ate EST.txt GT.txt"), std::string::npos) << out;
  EXPECT_EQ(run({"ate", g}), 2);
  EXPECT_EQ(run({"--frobnicate", g, g}), 2);
  EXPECT_EQ(run({"ate", tempPath("none.txt"), g}, nullptr, &err), 1);

  for (const char* c : {"segmentation", "classification", "nis"})
  {
    EXPECT_EQ(run({c, "--help"}, &out), 0) << c;
    EXPECT_NE(out.find(std::string("Usage: slam-eval ") + c), std::string::npos) << out;
    EXPECT_EQ(run({c}, nullptr, &err), 2) << c;
    EXPECT_EQ(run({c, "a", "b", "c", "d"}), 2) << c;
    EXPECT_EQ(run({c, "a", "--bogus", "1"}), 2) << c;
  }
  EXPECT_EQ(run({"segmentation", "p.csv", "l.txt", "--exclude", "-1"}), 2);
  EXPECT_EQ(run({"segmentation", "p.csv", "l.txt", "--exclude"}), 2);
  EXPECT_EQ(run({"classification", "c.csv"}, nullptr, &err), 2);  // neither --masks nor --points
  EXPECT_NE(err.find("exactly one of --masks"), std::string::npos) << err;
  EXPECT_EQ(run({"classification", "c.csv", "--masks", "d", "--points", "p"}), 2);
  EXPECT_EQ(run({"classification", "c.csv", "--masks", "d", "--radius", "1.5"}), 2);
  EXPECT_EQ(run({"nis", "s.csv", "--confidence", "1"}), 2);

  // Input errors: exit 1 naming the file (and line).
  EXPECT_EQ(run({"nis", tempPath("missing.csv")}, nullptr, &err), 1);
  EXPECT_NE(err.find("missing.csv"), std::string::npos) << err;
  const std::string labels = tempPath("labels.txt"), probs = tempPath("probs.csv");
  writeText(labels, "0.0 stationary\n0.033333 hovering\n");
  writeText(probs, "timestamp,stationary\n0.0,1\n");
  EXPECT_EQ(run({"segmentation", probs, labels}, nullptr, &err), 1);
  EXPECT_NE(err.find(labels + ":2"), std::string::npos) << err;
  writeText(labels, "5.0 stationary\n");
  EXPECT_EQ(run({"segmentation", probs, labels}, nullptr, &err), 1);  // no common timestamp
  EXPECT_NE(err.find(probs), std::string::npos) << err;
}
