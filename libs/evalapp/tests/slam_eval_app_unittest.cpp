/* Tests: runSlamEvalApp in process: subcommand dispatch, the old imm-eval form, usage errors (2)
 * and input errors (1). The program itself is run on small files by apps/slam-eval's test. */
#include <gtest/gtest.h>
#include <immslam/core/TTrajectory.h>
#include <immslam/evalapp/slam_eval_app.h>

#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

using namespace immslam;
using namespace immslam::eval;
using namespace immslam::evalapp;

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
  core::TTrajectory gt;
  for (int k = 0; k < 20; ++k)
    gt.push_back(core::TStampedPose{k / 30.0, Vec3(k, (k * k) % 5, (3 * k) % 4), Vec4(1, 0, 0, 0)});
  const std::string g = tempPath("gt.txt");
  core::writeTumTrajectory(gt, g);

  std::string out, outOld, err;
  EXPECT_EQ(run({"--help"}, &out), 0);
  for (const char* c : {"ate", "segmentation", "classification", "tracks", "nis"})
    EXPECT_NE(out.find(c), std::string::npos) << c;
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

  for (const char* c : {"segmentation", "classification", "tracks", "nis"})
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

TEST(SlamEvalApp, TracksAgainstPointsAfterTheCameraAlignment)
{
  // Camera ground truth and an estimate at half the scale: the Sim(3) of the cameras maps the
  // tracked positions onto the moving point exactly (error 0), the static row is counted apart.
  core::TTrajectory gt, est;
  for (int k = 0; k < 10; ++k)
  {
    const Vec3 p(0.1 * k, 0.02 * k * k, 0.05 * (k % 3));
    gt.push_back(core::TStampedPose{k / 15.0, p, Vec4(1, 0, 0, 0)});
    est.push_back(core::TStampedPose{k / 15.0, 0.5 * p, Vec4(1, 0, 0, 0)});
  }
  const std::string g = tempPath("tr_gt.txt"), e = tempPath("tr_est.txt"), pts = tempPath("tr_points.txt"),
                    tr = tempPath("tr_tracks.csv");
  core::writeTumTrajectory(gt, g);
  core::writeTumTrajectory(est, e);
  std::ostringstream ps, ts;
  ps << std::setprecision(17) << "# timestamp point_id kind x y z u v\n";
  ts << std::setprecision(17) << "timestamp,feature_id,x,y,z,u,v\n";
  for (int k = 0; k < 10; ++k)
  {
    ps << k / 15.0 << " 3 moving " << 1 + 0.1 * k << " 2 6 " << 100 + k << " 80\n" << k / 15.0 << " 4 static 0 0 5 10 10\n";
    ts << k / 15.0 << ",12," << 0.5 * (1 + 0.1 * k) << ",1,3," << 100 + k << ",80.5\n";
  }
  ts << 0.0 << ",13,0,0,2.5,10,11\n";
  writeText(pts, ps.str());
  writeText(tr, ts.str());
  std::string out, err;
  ASSERT_EQ(run({"tracks", tr, pts, "--est", e, "--gt", g}, &out, &err), 0) << err;
  EXPECT_NE(out.find("on a moving ground-truth point : 10 samples of 1 tracks"), std::string::npos) << out;
  EXPECT_NE(out.find("on a static ground-truth point : 1"), std::string::npos) << out;
  const auto at = out.find("RMS ");
  ASSERT_NE(at, std::string::npos) << out;
  EXPECT_LT(std::stod(out.substr(at + 4)), 1e-9) << out;
  EXPECT_EQ(run({"tracks", tr, pts, "--est", e}, nullptr, &err), 2);
  EXPECT_NE(err.find("--gt"), std::string::npos) << err;
  EXPECT_EQ(run({"tracks", tr, pts, "--est", e, "--gt", tempPath("none.txt")}, nullptr, &err), 1);

  // A rendered folder: without a truth source (no renderer in this library) a usage error naming
  // it; with one, its points are used, the report line printed and --gt defaults to the folder's.
  const std::string folder = tempPath("tr_rendered");
  std::filesystem::create_directories(folder);
  core::writeTumTrajectory(gt, (std::filesystem::path(folder) / "groundtruth.txt").string());
  EXPECT_EQ(run({"tracks", tr, folder, "--est", e}, nullptr, &err), 2);
  EXPECT_NE(err.find(folder), std::string::npos) << err;
  TSlamEvalTruthSources truth;
  std::string seenFolder;
  truth.renderedTrackTruth = [&](const std::string& f, const std::vector<core::TTrackSample>& samples, double,
                                 std::string& report) {
    seenFolder = f;
    report = "fake truth";
    std::vector<core::TGroundTruthPoint> truthPts;
    for (const auto& t : samples)
      if (t.featureId == 12) truthPts.push_back(core::TGroundTruthPoint{t.timestamp, 0, true, 2 * t.p_W, t.uv});
    return truthPts;
  };
  std::ostringstream o, e2;
  ASSERT_EQ(runSlamEvalApp({"slam-eval", "tracks", tr, folder, "--est", e}, o, e2, truth), 0) << e2.str();
  EXPECT_EQ(seenFolder, folder);
  EXPECT_NE(o.str().find("fake truth"), std::string::npos) << o.str();
  EXPECT_NE(o.str().find("on a moving ground-truth point : 10 samples of 1 tracks"), std::string::npos) << o.str();
  EXPECT_NE(o.str().find("no ground-truth point near     : 1"), std::string::npos) << o.str();
}
