/* End-to-end: moving objects seen by a camera that does not translate (issue 27; doc/shadow.md,
 * "Cameras that do not translate"). The rendered room and boxes of handheld-moving.ini, seen by a
 * camera at rest (ini/scenarios/still-movers.ini) and by one that only pans and tilts
 * (rotating-movers.ini), 240 frames each, the full system as shipped (with its watched features,
 * [system] watch_features = 10): the three-ray test is blind there (every ray
 * passes through one centre), so every decision comes from the depth-free test and the watched
 * features (doc/shadow.md). Truth: the renderer's masks. */
#include <gtest/gtest.h>
#include <immslam/eval/ate.h>
#include <immslam/eval/classification.h>
#include <immslam/eval/classification_truth.h>
#include <immslam/core/TTrajectory.h>
#include <immslam/sim/CSyntheticSource.h>

#include <cmath>
#include <cstdio>

#include "test_helpers.h"

namespace immslam::test
{
namespace
{
struct TMoversRun
{
  eval::TConfusionMatrix decisions;
  double rotationRmseDeg = 0;
  double maxTranslation = 0;  ///< largest distance of the estimated camera from its start (units)
};

TMoversRun runMovers(const std::string& scenario, const std::string& name)
{
  const auto out = outDir(name);
  EXPECT_EQ(runApp({sourceDir() + "/ini/imm7-shadow.ini", "--out", out, "--frames", "240", "--set",
                    "input.scenario=scenarios/" + scenario}),
            0);
  TMoversRun r;
  sim::CSyntheticSource src(sourceDir() + "/ini/scenarios/" + scenario, {}, 240);
  r.decisions = eval::classificationAgainstMasks(
                    eval::readClassificationsCsv(out + "/classifications.csv"),
                    [&](double t) -> std::optional<eval::TMaskImage> {
                      const cv::Mat mask = src.mask(static_cast<std::size_t>(std::llround(t * 30.0)));
                      return eval::TMaskImage::fromBuffer(mask.ptr<std::uint8_t>(0), mask.cols, mask.rows, mask.step);
                    },
                    1)
                    .confusion;
  const auto est = core::readTumTrajectory(out + "/trajectory.txt");
  const auto gt = src.groundTruth();
  EXPECT_TRUE(gt.has_value());
  if (gt) r.rotationRmseDeg = eval::computeAte(est, *gt, eval::EAlignment::None).rotationRmseDeg;
  for (const auto& p : est) r.maxTranslation = std::max(r.maxTranslation, (p.p_W_C - est.front().p_W_C).norm());
  const auto& c = r.decisions;
  std::printf("%s: %zu decisions; moving->static %zu/%zu, static->dynamic %zu/%zu; rotation RMSE %.3f deg; largest "
              "translation %.4f\n",
              scenario.c_str(), c.trulyDynamic() + c.trulyStatic(), c.dynamicAsStatic, c.trulyDynamic(), c.staticAsDynamic,
              c.trulyStatic(), r.rotationRmseDeg, r.maxTranslation);
  return r;
}
}  // namespace

TEST(MoversWithoutTranslation, CameraAtRestDecidesAndKeepsStill)
{
  // Measured (seed 7, 240 frames): 133 decisions, moving->static 2/34 (boxes slower than
  // static_min_velocity_px in the image while decided, below the power guarantee), static->dynamic
  // 7/99, rotation RMSE 0.011 deg, no translation. Before the depth-free test and the watched
  // features: no decision at all. Static decisions wait among dynamic features
  // (amongDynamic in CShadowFilter.cpp): before that rule this seed gave 154 decisions, moving->static 2/39,
  // static->dynamic 4/115; over the scene's seeds 1-10 (imm-render --frames 240) the rule gives
  // moving->static 13/505 against 23/527 and static->dynamic 46/1226 against 46/1264 (the fewer
  // decisions: features waiting near a box hold watched slots). With the memory of where motion was
  // seen (nearRecentMotion): this seed 142 decisions, 1/27, 7/115 before; seeds 1-10 moving->static
  // 9/466 against 13/505, static->dynamic 41/1029 against 46/1226. Static decisions of new features
  // now wait for a track of 30 frames while the camera does not translate (doc/shadow.md, "Decision
  // rules"; this replaced the memory): this seed 84 decisions, moving->static 0/21, static->dynamic
  // 4/63 (fewer decisions: a watched feature holds its slot for 30 frames); seeds 1-10 moving->static
  // 0/339, static->dynamic 38/559. Dynamic decisions now need a track that follows one point
  // (min_point_ncc): this seed 81 decisions, moving->static 0/20, static->dynamic 2/61 (4/63 without the
  // check); seeds 1-10 moving->static 1/311, static->dynamic 24/573 (51/597). Limits at about 1.2 x.
  const TMoversRun r = runMovers("still-movers.ini", "movers_still");
  EXPECT_GE(r.decisions.trulyDynamic(), 17u) << "the boxes must be seen and decided";
  EXPECT_GE(r.decisions.trulyStatic(), 52u);
  EXPECT_LE(r.decisions.movingAsStaticRate(), 0.062);
  EXPECT_LE(r.decisions.staticAsDynamicRate(), 0.04);
  EXPECT_LT(r.rotationRmseDeg, 0.013);
  EXPECT_LT(r.maxTranslation, 1e-3);
}

TEST(MoversWithoutTranslation, RotatingCameraDecidesAndFollowsTheRoom)
{
  // Measured (seed 7, 240 frames): 156 decisions, moving->static 3/27, static->dynamic 3/129,
  // rotation RMSE 0.020 deg, largest translation 0.0001 (before static decisions waited among dynamic
  // features: 149 decisions, 5/33, 4/116; over seeds 1-10, moving->static 17/365 against 18/371,
  // static->dynamic 47/1300 against 56/1298; before they waited where motion was seen lately: 161,
  // 4/25, 6/136; seeds 1-10 moving->static 14/348 against 17/365, static->dynamic 50/1166 against
  // 47/1300; before static decisions of new features waited for a track of 30 frames while the
  // camera does not translate: 142 decisions, 3/27, 3/129 before; now 79, 1/18, 1/61, seeds 1-10
  // moving->static 0/239 against 14/348, static->dynamic 24/503 against 50/1166; with dynamic decisions
  // needing a track that follows one point, min_point_ncc: 78, 1/18, 0/60, seeds 1-10 moving->static
  // 2/215, static->dynamic 13/486). Limits at about 1.2 x.
  const TMoversRun r = runMovers("rotating-movers.ini", "movers_rotating");
  EXPECT_GE(r.decisions.trulyDynamic(), 15u) << "the boxes must be seen and decided";
  EXPECT_GE(r.decisions.trulyStatic(), 50u);
  EXPECT_LE(r.decisions.movingAsStaticRate(), 0.182);
  EXPECT_LE(r.decisions.staticAsDynamicRate(), 0.053);
  EXPECT_LT(r.rotationRmseDeg, 0.027);
  EXPECT_LT(r.maxTranslation, 1e-3);
}
}  // namespace immslam::test
