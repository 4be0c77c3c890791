/* Tests: TUM trajectory files (core/TTrajectory.h): exact round trip, field order, comments,
 * normalization, errors naming file and line; pose interpolation and the completion of a trajectory. */
#include <gtest/gtest.h>
#include <immslam/core/TTrajectory.h>
#include <immslam/math/quaternion.h>
#include <immslam/math/random_samples.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <stdexcept>

using namespace immslam;

namespace
{
using math::randomQuat;
using math::randomVec3;
std::string tempPath(const std::string& name)
{
  return (std::filesystem::path(::testing::TempDir()) / ("immslam_core_" + name)).string();
}
void writeText(const std::string& path, const std::string& text)
{
  std::ofstream f(path);
  f << text;
}
}  // namespace

TEST(TumIO, RoundTripIsExact)
{
  std::mt19937 rng(1);
  core::TTrajectory tr;
  for (int k = 0; k < 50; ++k)
  {
    core::TStampedPose p;
    p.timestamp = 1305031102.175304 + 0.033 * k;
    p.p_W_C = randomVec3(rng, 10.0);
    p.q_W_C = randomQuat(rng);
    tr.push_back(p);
  }
  tr[3].p_W_C = Vec3(1e-12, -123456.789, 0.1);
  const std::string path = tempPath("roundtrip.txt");
  core::writeTumTrajectory(tr, path);
  const core::TTrajectory back = core::readTumTrajectory(path);
  ASSERT_EQ(back.size(), tr.size());
  for (size_t k = 0; k < tr.size(); ++k)
  {
    EXPECT_NEAR(back[k].timestamp, tr[k].timestamp, 5e-7);
    EXPECT_LT((back[k].p_W_C - tr[k].p_W_C).norm(), 1e-9);
    // The read quaternion is re-normalized: equal to within rounding.
    EXPECT_LT((back[k].q_W_C - tr[k].q_W_C).norm(), 1e-15);
  }
  EXPECT_EQ(back[3].p_W_C, tr[3].p_W_C);  // positions are bit exact
}

TEST(TumIO, FormatOrderCommentsAndNormalization)
{
  core::TStampedPose p;
  p.timestamp = 12.5;
  p.p_W_C = Vec3(1, -2, 0.5);
  p.q_W_C = Vec4(0.5, 0.5, -0.5, 0.5);  // [qw qx qy qz]
  EXPECT_EQ(core::formatTumLine(p), "12.500000 1 -2 0.5 0.5 -0.5 0.5 0.5");

  const std::string path = tempPath("order.txt");
  writeText(path, "# timestamp tx ty tz qx qy qz qw\n\n  \t\n1.0 1 2 3 0 0 0 2\r\n"
                  "2.0,4,5,6,0,2,0,0\n  # indented comment\n3 +1 2e0 3 0 0 1 0\n");
  const core::TTrajectory tr = core::readTumTrajectory(path);
  ASSERT_EQ(tr.size(), 3u);
  EXPECT_EQ(tr[0].q_W_C, Vec4(1, 0, 0, 0));  // qw = 2 normalized
  EXPECT_EQ(tr[1].q_W_C, Vec4(0, 0, 1, 0));  // qy = 2 normalized
  EXPECT_EQ(tr[1].p_W_C, Vec3(4, 5, 6));
  EXPECT_EQ(tr[2].p_W_C, Vec3(1, 2, 3));
  EXPECT_EQ(tr[2].q_W_C, Vec4(0, 0, 0, 1));
  // Components near DBL_MAX: the norm must not overflow (found by fuzzing, tests/fuzz).
  writeText(path, "1 0 0 0 1e308 1e308 0 1e308\n");
  const core::TTrajectory big = core::readTumTrajectory(path);
  EXPECT_NEAR(big[0].q_W_C.norm(), 1.0, 1e-15);
  EXPECT_NEAR(big[0].q_W_C[0], 1 / std::sqrt(3.0), 1e-15);
}

TEST(TumIO, MalformedLineErrorNamesFileAndLine)
{
  const std::string path = tempPath("bad.txt");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"1 0 0 0 0 0 0 1\n# c\n2 0 0 0 0 0 1\n", ":3:"},             // 7 fields
      {"1 0 0 0 0 0 0 1\n2 0 0 x 0 0 0 1\n", ":2:"},                // not a number
      {"1 0 0 0 0 0 0 1 5\n", ":1:"},                               // 9 fields
      {"\n\n1 0 0 0 0 0 0 0\n", ":3:"},                             // zero quaternion
      {"1 0 0 nan 0 0 0 1\n", ":1:"},                               // not finite
      {"1 0 0 0.5.5 0 0 0 1\n", ":1:"},                             // trailing junk
  };
  for (const auto& [text, where] : cases)
  {
    writeText(path, text);
    try
    {
      core::readTumTrajectory(path);
      ADD_FAILURE() << "no error for: " << text;
    }
    catch (const std::runtime_error& e)
    {
      EXPECT_NE(std::string(e.what()).find(path + where), std::string::npos) << e.what();
    }
  }
  try
  {
    core::readTumTrajectory(tempPath("does_not_exist.txt"));
    ADD_FAILURE() << "no error for a missing file";
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find("does_not_exist.txt"), std::string::npos);
  }
}

namespace
{
core::TStampedPose pose(double t, const Vec3& p, const Vec3& rotationVector)
{
  core::TStampedPose s;
  s.timestamp = t;
  s.p_W_C = p;
  s.q_W_C = math::quatFromRotationVector(rotationVector);
  return s;
}
}  // namespace

TEST(PoseInterpolation, ConstantVelocityInTimeAndClampedOutside)
{
  const core::TStampedPose a = pose(1.0, Vec3(0, 0, 0), Vec3(0, 0, 0));
  const core::TStampedPose b = pose(3.0, Vec3(2, -4, 6), Vec3(0, 0.8, 0));
  const core::TStampedPose m = core::interpolatePose(a, b, 1.5);  // a quarter of the way
  EXPECT_EQ(m.timestamp, 1.5);
  EXPECT_LT((m.p_W_C - Vec3(0.5, -1, 1.5)).norm(), 1e-12);
  EXPECT_LT((math::quatToRotationVector(m.q_W_C) - Vec3(0, 0.2, 0)).norm(), 1e-12);
  const core::TStampedPose before = core::interpolatePose(a, b, 0.0), after = core::interpolatePose(a, b, 9.0);
  EXPECT_EQ(before.timestamp, 0.0);
  EXPECT_LT((before.p_W_C - a.p_W_C).norm(), 1e-12);
  EXPECT_LT((after.p_W_C - b.p_W_C).norm(), 1e-12);
  EXPECT_LT((math::quatToRotationVector(after.q_W_C) - Vec3(0, 0.8, 0)).norm(), 1e-12);
}

TEST(PoseInterpolation, CarryKeepsThePoseRelativeToItsReference)
{
  std::mt19937 rng(3);
  core::TStampedPose from, to, p;
  from.p_W_C = randomVec3(rng, 5.0), from.q_W_C = randomQuat(rng);
  to.p_W_C = randomVec3(rng, 5.0), to.q_W_C = randomQuat(rng);
  p.p_W_C = randomVec3(rng, 5.0), p.q_W_C = randomQuat(rng), p.timestamp = 7;
  const core::TStampedPose c = core::carryPose(to, from, p);
  EXPECT_EQ(c.timestamp, 7.0);
  // The relative pose from^-1 p equals to^-1 c.
  const Mat3 Rf = math::quatToRotation(from.q_W_C), Rt = math::quatToRotation(to.q_W_C);
  EXPECT_LT((Rf.transpose() * (p.p_W_C - from.p_W_C) - Rt.transpose() * (c.p_W_C - to.p_W_C)).norm(), 1e-12);
  EXPECT_LT((Rf.transpose() * math::quatToRotation(p.q_W_C) - Rt.transpose() * math::quatToRotation(c.q_W_C)).norm(),
            1e-12);
  // Carried onto itself: unchanged.
  EXPECT_LT((core::carryPose(from, from, p).p_W_C - p.p_W_C).norm(), 1e-12);
}

TEST(PoseInterpolation, CompleteTrajectoryFillsTheFramesLeftOut)
{
  // `all`: 8 frames moving along x; placed: frames 2, 3 and 6 only, shifted by +10 in y (another
  // estimate). Frames 4-5 between placed poses: interpolated; 0-1 before and 7 after: carried by all's motion.
  core::TTrajectory all, placed;
  for (int i = 0; i < 8; ++i) all.push_back(pose(0.1 * i, Vec3(i, 0, 0), Vec3(0, 0, 0)));
  for (int i : {2, 3, 6}) placed.push_back(pose(0.1 * i, Vec3(i, 10, 0), Vec3(0, 0, 0)));
  placed[2].p_W_C.z() = 3;  // frame 6 off in z: the interpolation shows
  const core::TTrajectory out = core::completeTrajectory(placed, all);
  ASSERT_EQ(out.size(), all.size());
  for (std::size_t i = 0; i < out.size(); ++i) EXPECT_EQ(out[i].timestamp, all[i].timestamp) << i;
  EXPECT_LT((out[0].p_W_C - Vec3(0, 10, 0)).norm(), 1e-9);
  EXPECT_LT((out[1].p_W_C - Vec3(1, 10, 0)).norm(), 1e-9);
  EXPECT_EQ(out[2].p_W_C, placed[0].p_W_C);
  EXPECT_LT((out[4].p_W_C - Vec3(4, 10, 1)).norm(), 1e-9);
  EXPECT_LT((out[5].p_W_C - Vec3(5, 10, 2)).norm(), 1e-9);
  EXPECT_EQ(out[6].p_W_C, placed[2].p_W_C);
  EXPECT_LT((out[7].p_W_C - Vec3(7, 10, 3)).norm(), 1e-9);
  // Nothing placed: `all` as it is.
  EXPECT_EQ(core::completeTrajectory({}, all)[5].p_W_C, all[5].p_W_C);
}
