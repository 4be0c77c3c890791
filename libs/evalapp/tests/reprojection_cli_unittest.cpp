/* Tests: `slam-eval reprojection` in process: the report, --refine writing the bundle-adjusted
 * trajectory, and the usage and input errors. */
#include <gtest/gtest.h>
#include <immslam/evalapp/slam_eval_app.h>
#include <immslam/refine/bundle_problem.h>

#include "bundle_test_scene.h"

#include <filesystem>
#include <fstream>
#include <sstream>

using namespace immslam;
using namespace immslam::refine;
using namespace immslam::refine::test;

namespace
{
std::string tempPath(const std::string& name)
{
  return (std::filesystem::path(::testing::TempDir()) / ("immslam_reproj_" + name)).string();
}
}  // namespace

TEST(Reprojection, CommandLine)
{
  const TScene s = makeScene(30, 20);
  const auto cam = pinhole();
  const std::string searches = tempPath("searches.csv"), poses = tempPath("poses.txt"), calib = tempPath("calib.txt"),
                    refined = tempPath("refined.txt");
  {
    std::ofstream f(searches);
    f << "timestamp,feature_id,h_u,h_v,s_uu,s_uv,s_vv,found,z_u,z_v,score,status\n";
    f.precision(17);
    for (const auto& r : measure(s, *cam, 0.3))
      f << r.timestamp << "," << r.featureId << "," << r.h.x() << "," << r.h.y() << ",1,0,1,1," << r.z.x() << ","
        << r.z.y() << ",0.99," << eval::searchStatusName(r.status) << "\n";
  }
  core::writeTumTrajectory(bend(s.poses, 2.0), poses);
  std::ofstream(calib) << "# test\n" << cam->toCalibLine() << "\n";

  std::ostringstream out, err;
  ASSERT_EQ(evalapp::runSlamEvalApp({"slam-eval", "reprojection", searches, poses, "--calib", calib, "--refine", refined}, out,
                           err),
            0)
      << err.str();
  EXPECT_NE(out.str().find("reprojection RMS"), std::string::npos) << out.str();
  EXPECT_NE(out.str().find("after bundle adjustment"), std::string::npos) << out.str();
  EXPECT_EQ(core::readTumTrajectory(refined).size(), s.poses.size());
  const auto rowsBack = eval::readSearchesCsv(searches);
  EXPECT_GT(reprojectionStats(makeBundleProblem(rowsBack, bend(s.poses, 2.0), *cam, 1e-4, 8)).rmsPx, 2.0);
  EXPECT_LT(reprojectionStats(makeBundleProblem(rowsBack, core::readTumTrajectory(refined), *cam, 1e-4, 8)).rmsPx, 0.5);

  std::ostringstream o2, e2;
  EXPECT_EQ(evalapp::runSlamEvalApp({"slam-eval", "reprojection", searches, poses}, o2, e2), 2);
  EXPECT_NE(e2.str().find("--calib is required"), std::string::npos) << e2.str();
  std::ostringstream o3, e3;
  EXPECT_EQ(evalapp::runSlamEvalApp({"slam-eval", "reprojection", searches, poses, "--calib", tempPath("missing.txt")}, o3, e3),
            1);
  EXPECT_NE(e3.str().find("missing.txt"), std::string::npos) << e3.str();
  std::ostringstream o4, e4;
  EXPECT_EQ(evalapp::runSlamEvalApp({"slam-eval", "reprojection", searches, poses, "--calib", calib, "--min-views", "1"}, o4, e4),
            2);
}

