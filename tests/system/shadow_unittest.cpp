/* MonoSLAMBOT (paper 2) at system level: static/dynamic classification against ground truth, and the
 * map kept clean of moving objects (Fig. 5 as numbers). */
#include "test_helpers.h"

#include <immslam/eval/classification_truth.h>
#include <immslam/sim/CSimulator.h>
#include <immslam/sim/CSyntheticSource.h>
#include <immslam/sim/TScenario.h>

#include <cmath>
#include <optional>

using namespace immslam;
using namespace immslam::test;

TEST(ShadowSystem, MonoslammotSynth19ClassificationAgainstPointGroundTruth)
{
  if (!haveSharedData("monoslammot_synth19")) GTEST_SKIP() << "../shared/data/monoslammot_synth19 is absent";
  const auto out = outDir("synth19_full");
  app::TRunSummary s;
  ASSERT_EQ(runApp({sourceDir() + "/ini/imm7-shadow.ini", sharedData("monoslammot_synth19"), "--out", out, "--set",
                    "output.plots=false"},
                   &s),
            0);
  // Ground truth: per timestamp the projections of the static and moving points; a decision farther
  // than 3 px from every point is on a corner that is not one of them (unmatched).
  const eval::TClassificationResult res = eval::classificationAgainstPoints(
      eval::readClassificationsCsv(out + "/classifications.csv"),
      eval::readPointsGroundTruth(sharedData("monoslammot_synth19") + "/points_groundtruth.txt"), 3.0);
  const eval::TConfusionMatrix& c = res.confusion;
  std::printf("synth19: moving->static %zu/%zu (%.3f), static->dynamic %zu/%zu (%.3f), %zu decisions on other corners; "
              "ATE %.3f %% of path\n",
              c.dynamicAsStatic, c.trulyDynamic(), c.movingAsStaticRate(), c.staticAsDynamic, c.trulyStatic(),
              c.staticAsDynamicRate(), res.unmatched, 100 * s.ate->rmseOverPath);
  EXPECT_GE(c.trulyDynamic(), 10u);
  EXPECT_LE(c.movingAsStaticRate(), 0.01);
  EXPECT_LE(c.staticAsDynamicRate(), 0.05);
}

TEST(ShadowSystem, RenderedMovingObjectsDoNotCorruptTheMap)
{
  // Same camera path with and without moving objects (handheld.ini / handheld-moving.ini).
  app::TRunSummary withShadow, still, noShadow, singleMoving, singleStill;
  const auto run = [](const std::string& cfg, const std::string& scen, const std::string& name, app::TRunSummary* s) {
    const auto out = outDir(name);
    EXPECT_EQ(runApp({sourceDir() + "/ini/" + cfg, "--out", out, "--set", "input.scenario=scenarios/" + scen, "--set",
                      "output.plots=false"},
                     s),
              0);
    return out;
  };
  const auto outMoving = run("imm7-shadow.ini", "handheld-moving.ini", "hm_full", &withShadow);
  run("imm7-shadow.ini", "handheld.ini", "hh_full", &still);
  run("imm7.ini", "handheld-moving.ini", "hm_noshadow", &noShadow);
  run("single.ini", "handheld-moving.ini", "hm_single", &singleMoving);
  run("single.ini", "handheld.ini", "hh_single", &singleStill);
  ASSERT_TRUE(withShadow.ate && still.ate && noShadow.ate && singleMoving.ate && singleStill.ate);

  // Classification against the renderer's masks.
  sim::CSyntheticSource src(sourceDir() + "/ini/scenarios/handheld-moving.ini");
  const eval::TClassificationResult res = eval::classificationAgainstMasks(
      eval::readClassificationsCsv(outMoving + "/classifications.csv"),
      [&](double t) -> std::optional<eval::TMaskImage> {
        const cv::Mat mask = src.mask(static_cast<std::size_t>(std::llround(t * 30.0)));
        return eval::TMaskImage::fromBuffer(mask.ptr<std::uint8_t>(0), mask.cols, mask.rows, mask.step);
      },
      1);
  const eval::TConfusionMatrix& c = res.confusion;
  std::printf("handheld-moving: moving->static %zu/%zu, static->dynamic %zu/%zu; ATE/path: full system %.3f %% with moving "
              "objects vs %.3f %% without (ratio %.2f); IMM without shadow filter %.3f %%; single model %.3f %% with "
              "moving objects vs %.3f %% without\n",
              c.dynamicAsStatic, c.trulyDynamic(), c.staticAsDynamic, c.trulyStatic(),
              100 * withShadow.ate->rmseOverPath, 100 * still.ate->rmseOverPath,
              withShadow.ate->rmse / still.ate->rmse, 100 * noShadow.ate->rmseOverPath,
              100 * singleMoving.ate->rmseOverPath, 100 * singleStill.ate->rmseOverPath);
  EXPECT_EQ(c.dynamicAsStatic, 0u);
  EXPECT_LE(c.staticAsDynamicRate(), 0.05);
  // This seed (7) alone: 1.17 % with the shipped bank (imm.general_entry = evidence; 0.74 % with
  // "markov", which is worse on average: doc/imm.md). The accuracy claim is tested over five seeds below.
  EXPECT_LE(withShadow.ate->rmseOverPath, 0.015);
}

TEST(ShadowSystem, MovingObjectsOverFiveSeeds)
{
  // Fig. 5 of paper 2 as numbers, the seeds of share/scripts/moving-objects-ate.sh: the full system on
  // the hand-held path with moving boxes, and on the same path (same seed) without them.
  double sumMoving = 0, sumStill = 0;
  const std::vector<int> seeds{7, 11, 23, 42, 101};
  for (const int seed : seeds)
  {
    double ate[2] = {0, 0};
    for (const bool moving : {false, true})
    {
      const std::string scen = moving ? "handheld-moving" : "handheld";
      const std::string name = scen + "-" + std::to_string(seed);
      const std::string data = outDir("data-" + name);
      sim::CSimulator(sim::TScenario::loadFile(sourceDir() + "/ini/scenarios/" + scen + ".ini",
                                               {"scenario.seed=" + std::to_string(seed)}))
          .writeDataset(data);
      app::TRunSummary s;
      ASSERT_EQ(runApp({sourceDir() + "/ini/imm7-shadow.ini", data, "--out", outDir("out-" + name), "--set",
                        "output.plots=false"},
                       &s),
                0);
      ASSERT_TRUE(s.ate);
      ate[moving] = s.ate->rmseOverPath;
    }
    std::printf("seed %d: full system ATE %.3f %% of path without moving objects, %.3f %% with\n", seed, 100 * ate[0],
                100 * ate[1]);
    EXPECT_LE(ate[1], 0.015) << "seed " << seed;
    sumStill += ate[0];
    sumMoving += ate[1];
  }
  const double n = static_cast<double>(seeds.size());
  std::printf("mean over %zu seeds: %.3f %% without, %.3f %% with moving objects (ratio %.2f)\n", seeds.size(),
              100 * sumStill / n, 100 * sumMoving / n, sumMoving / sumStill);
  EXPECT_LE(sumMoving / n, 0.01);
  EXPECT_LE(sumMoving / sumStill, 1.6);  // measured 1.47 (the paper's claim, <= 1.2, is not met: doc/shadow.md)
}
