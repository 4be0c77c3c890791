/* MonoSLAMBOT (paper 2) at system level: static/dynamic classification against ground truth, and the
 * map kept clean of moving objects (Fig. 5 as numbers), on rendered scenes and on real video with
 * pasted moving objects. */
#include "test_helpers.h"

#include <immslam/eval/ate.h>
#include <immslam/eval/classification_truth.h>
#include <immslam/sim/CSimulator.h>
#include <immslam/sim/CSyntheticSource.h>
#include <immslam/sim/TScenario.h>
#include <immslam/sim/composite.h>
#include <immslam/sim/rotated_view.h>
#include <immslam/eval/search_nis.h>
#include <immslam/eval/segmentation.h>

#include <zlib.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <map>
#include <numeric>
#include <optional>
#include <cstdlib>
#include <fstream>

using namespace immslam;
using namespace immslam::test;

TEST(ShadowSystem, MonoslammotSynth19ClassificationAgainstPointGroundTruth)
{
  if (!haveSharedData("monoslammot_synth19")) GTEST_SKIP() << "../shared/data/monoslammot_synth19 is absent";
  const auto out = outDir("synth19_full");
  app::TRunSummary s;
  ASSERT_EQ(runApp({sourceDir() + "/ini/imm7-shadow.ini", sharedData("monoslammot_synth19"), "--out", out},
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
  // Measured: moving->static 0 of 21, static->dynamic 1 of 133 (0.8 %), ATE 0.362 % of path; the
  // limits are ~1.2x an earlier, worse measurement (2 of 129, 1.6 %; 0.556 %). 21 decisions on movers, not more: a lone dynamic verdict of a translating
  // camera waits for another feature nearby that moves, and the movers of this simulated world are
  // points that move each on its own path (doc/shadow.md, "Decision rules").
  EXPECT_GE(c.trulyDynamic(), 18u);
  EXPECT_LE(c.movingAsStaticRate(), 0.01);
  EXPECT_LE(c.staticAsDynamicRate(), 0.019);
  ASSERT_TRUE(s.ate);
  EXPECT_LE(s.ate->rmseOverPath, 0.0067);
}

TEST(ShadowSystem, KnownAssociationReproducesFig5OnSynth19)
{
  // The paper's Fig. 5 experiment as published: a simulated world of static and moving points, "data
  // association performed manually" ([input] known_association: synth19's own point tracks), (a) the
  // classic filter with the dynamic points disabled, (b) the classic filter with them, (c) with the
  // shadow filter. doc/shadow.md, "Fig. 5 with known data association".
  if (!haveSharedData("monoslammot_synth19")) GTEST_SKIP() << "../shared/data/monoslammot_synth19 is absent";
  const std::string data = sharedData("monoslammot_synth19");
  const std::string points = data + "/points_groundtruth.txt";
  const auto truth = eval::readPointsGroundTruth(points);
  std::map<std::string, double> ate;
  std::map<std::string, eval::TConfusionMatrix> conf;
  for (const std::string cfg : {"single", "single-shadow", "imm7-shadow"})
    for (const std::string kinds : {"static", "all"})
    {
      const std::string name = cfg + "-" + kinds;
      const std::string out = outDir("known-association-" + name);
      app::TRunSummary s;
      // The paper's protocol: the classic filter uses every measurement given (no gate, no RANSAC),
      // starts on static points only (Sec. II) and takes no unresolved feature (no release), so only
      // the shadow filter's decisions stand between it and the moving points; the paper's filter
      // decides a point that moves alone at once (its moving points move each on its own path).
      ASSERT_EQ(runApp({sourceDir() + "/ini/" + cfg + ".ini", data, "--out", out,
                        "--set", "input.known_association=" + points, "--set", "input.known_association_kinds=" + kinds,
                        "--set", "input.known_association_robust=false", "--set",
                        "input.known_association_first_map=static", "--set", "system.starved_below=0",
                        "--set", "shadow.decide_lone_dynamic=true"},
                       &s),
                0)
          << name;
      ASSERT_TRUE(s.ate) << name;
      EXPECT_EQ(s.framesWithoutTracks, 0u) << name;
      ate[name] = s.ate->rmseOverPath;
      if (cfg != "single")
        conf[name] = eval::classificationAgainstPoints(eval::readClassificationsCsv(out + "/classifications.csv"), truth, 3.0)
                         .confusion;
    }
  for (const auto& [name, c] : conf)
    std::printf("%s: ATE %.2f %% of path; moving->static %zu/%zu, static->dynamic %zu/%zu\n", name.c_str(),
                100 * ate[name], c.dynamicAsStatic, c.trulyDynamic(), c.staticAsDynamic, c.trulyStatic());
  std::printf("single: %.2f %% (a, static points) %.2f %% (b, all points)\n", 100 * ate["single-static"],
              100 * ate["single-all"]);
  // (b) fails: the moving points in the filter multiply its error.
  EXPECT_GE(ate["single-all"], 3 * ate["single-static"]);
  // (c), MonoSLAMBOT as published: the accuracy of the same system in a static world (the 1.2
  // criterion). With the IMM bank, one sequence's ratio is noise (0.99-1.39 with and without
  // releases; the 120 rendered seeds of doc/shadow.md measure it): both beat (a) by far.
  EXPECT_LE(ate["single-shadow-all"], 1.2 * ate["single-shadow-static"]);
  for (const std::string cfg : {"single-shadow", "imm7-shadow"})
  {
    EXPECT_LE(ate[cfg + "-all"], 0.75 * ate["single-static"]) << cfg;
    const auto& c = conf[cfg + "-all"];
    EXPECT_GE(c.trulyDynamic(), 40u) << cfg;  // measured 50 / 52
    EXPECT_LE(c.movingAsStaticRate(), 0.01) << cfg;
  }
  // Absolute limits at ~1.2x the measured figures (2026-11-27): (a) 2.04 %, (b) 8.30 % of path; (c)
  // single-shadow 0.77 % (static points only 0.79 %), imm7-shadow 1.10 % (0.79 %); static points
  // called dynamic 3 of 138 (single-shadow) and 28 of 143 (imm7-shadow).
  EXPECT_LE(ate["single-static"], 0.0245);
  EXPECT_LE(ate["single-shadow-all"], 0.0093);
  EXPECT_LE(ate["imm7-shadow-all"], 0.0132);
  EXPECT_LE(conf["single-shadow-all"].staticAsDynamicRate(), 0.027);
  EXPECT_LE(conf["imm7-shadow-all"].staticAsDynamicRate(), 0.235);
}

TEST(ShadowSystem, RenderedMovingObjectsDoNotCorruptTheMap)
{
  // Same camera path with and without moving objects (handheld.ini / handheld-moving.ini).
  app::TRunSummary withShadow, still, noShadow, singleMoving, singleStill;
  const auto run = [](const std::string& cfg, const std::string& scen, const std::string& name, app::TRunSummary* s) {
    const auto out = outDir(name);
    EXPECT_EQ(runApp({sourceDir() + "/ini/" + cfg, "--out", out, "--set", "input.scenario=scenarios/" + scen},
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
  EXPECT_LE(c.staticAsDynamicRate(), 0.05);  // measured 0 of 30
  // This seed (7) alone, limits at ~1.2x the figures measured 2026-11-27: full system 0.892 % with the
  // moving objects, 0.872 % without; IMM without shadow filter 1.032 %; the single model 1.926 % with
  // them, 0.770 % without. The five-seed spread of the full system is in the test below.
  EXPECT_GE(c.trulyDynamic(), 3u);
  EXPECT_LE(withShadow.ate->rmseOverPath, 0.0107);
  EXPECT_LE(still.ate->rmseOverPath, 0.0105);
  EXPECT_LE(noShadow.ate->rmseOverPath, 0.0124);
  EXPECT_LE(singleMoving.ate->rmseOverPath, 0.0232);
  EXPECT_LE(singleStill.ate->rmseOverPath, 0.0093);
}

TEST(ShadowSystem, MovingObjectsOverFiveSeeds)
{
  // Fig. 5 of paper 2 as numbers, the seeds of share/experiments/moving-objects-ate.sh: the full system on
  // the hand-held path with moving boxes, and on the same path (same seed) without them; for the
  // filter's trajectory and for the offline refinement of the run's own matches
  // ([output] refine_trajectory: the shadow filter kept the boxes' measurements out of them).
  double sumMoving = 0, sumStill = 0, sumMovingRefined = 0, sumStillRefined = 0;
  const std::vector<int> seeds{7, 11, 23, 42, 101};
  for (const int seed : seeds)
  {
    double ate[2] = {0, 0}, refined[2] = {0, 0};
    for (const bool moving : {false, true})
    {
      const std::string scen = moving ? "handheld-moving" : "handheld";
      const std::string name = scen + "-" + std::to_string(seed);
      const std::string data = outDir("data-" + name);
      sim::CSimulator(sim::TScenario::loadFile(sourceDir() + "/ini/scenarios/" + scen + ".ini",
                                               {"scenario.seed=" + std::to_string(seed)}))
          .writeDataset(data);
      app::TRunSummary s;
      ASSERT_EQ(runApp({sourceDir() + "/ini/imm7-shadow.ini", data, "--out", outDir("out-" + name), "--set", "output.refine_trajectory=true"},
                       &s),
                0);
      ASSERT_TRUE(s.ate);
      ASSERT_TRUE(s.ateRefined);
      ate[moving] = s.ate->rmseOverPath;
      refined[moving] = s.ateRefined->rmseOverPath;
    }
    std::printf("seed %d: full system ATE %.3f %% of path without moving objects, %.3f %% with; refined %.3f %%, "
                "%.3f %%\n",
                seed, 100 * ate[0], 100 * ate[1], 100 * refined[0], 100 * refined[1]);
    // ~1.2x each seed's measured ATE with moving objects: seeds 7 / 11 / 23 / 42 / 101: 0.728 / 1.099 /
    // 1.496 / 0.583 / 0.647 % (without them 0.873 / 0.604 / 0.494 / 0.432 / 0.734 %); before static
    // decisions waited for a track of 30 frames while the camera does not translate 0.892 / 1.086 /
    // 1.030 / 0.572 / 0.920 % (mean 0.900 against 0.911 now; without them 0.872 / 0.839 / 0.534 / 0.417
    // / 0.720 %).
    static const std::map<int, double> limit{{7, 0.0088}, {11, 0.0132}, {23, 0.0180}, {42, 0.0070}, {101, 0.0111}};
    EXPECT_LE(ate[1], limit.at(seed)) << "seed " << seed;
    EXPECT_LT(refined[1], ate[1]) << "seed " << seed;
    sumStill += ate[0];
    sumMoving += ate[1];
    sumStillRefined += refined[0];
    sumMovingRefined += refined[1];
  }
  const double n = static_cast<double>(seeds.size());
  std::printf("mean over %zu seeds: %.3f %% without, %.3f %% with moving objects (ratio %.2f); refined %.3f %%, "
              "%.3f %% (ratio %.2f)\n",
              seeds.size(), 100 * sumStill / n, 100 * sumMoving / n, sumMoving / sumStill, 100 * sumStillRefined / n,
              100 * sumMovingRefined / n, sumMovingRefined / sumStillRefined);
  // Measured 2026-11-27: mean 0.676 % without, 0.900 % with (ratio 1.33; the paper's claim, <= 1.2,
  // is not met: doc/shadow.md); refined 0.192 % and 0.193 % (ratio 1.00). Limits ~1.2x.
  EXPECT_LE(sumMoving / n, 0.0108);
  EXPECT_LE(sumStill / n, 0.0081);
  EXPECT_LE(sumMoving / sumStill, 1.6);
  EXPECT_LE(sumMovingRefined / n, 0.0023);
  EXPECT_LE(sumStillRefined / n, 0.0023);
  EXPECT_LE(sumMovingRefined / sumStillRefined, 1.2);
}

TEST(ShadowSystem, ExclusionMasksDisableTheMovingObjectsAsInFig5a)
{
  // The paper's Fig. 5(a): the SLAM with the dynamic features "disabled". [input] exclusion_masks
  // with the renderer's object masks: no SLAM match and no shadow-filter decision on a moving object,
  // for the IMM without shadow filter and for the full system (doc/shadow.md, "Fig. 5(a)").
  const std::string data = outDir("data-excl-handheld-moving-7");
  sim::CSimulator(sim::TScenario::loadFile(sourceDir() + "/ini/scenarios/handheld-moving.ini", {"scenario.seed=7"}))
      .writeDataset(data);
  const eval::TMaskProvider maskAt = eval::maskFolderProvider(data);
  std::map<std::string, double> ate;
  for (const std::string cfg : {"imm7.ini", "imm7-shadow.ini"})
  {
    const std::string out = outDir("excl-" + cfg);
    app::TRunSummary s;
    ASSERT_EQ(runApp({sourceDir() + "/ini/" + cfg, data, "--out", out, "--set",
                      "output.search_log=true", "--set", "input.exclusion_masks=" + data},
                     &s),
              0);
    ASSERT_TRUE(s.ate);
    ate[cfg] = s.ate->rmseOverPath;
    // No measurement used in the update within patch_half_size (5 px) of an object pixel.
    std::size_t used = 0, onObject = 0;
    for (const auto& r : eval::readSearchesCsv(out + "/searches.csv"))
      if (r.usedInUpdate())
      {
        ++used;
        const auto m = maskAt(r.timestamp);
        ASSERT_TRUE(m) << r.timestamp;
        onObject += m->movingNear(r.z, 5) ? 1 : 0;
      }
    EXPECT_GT(used, 5000u) << cfg;
    EXPECT_EQ(onObject, 0u) << cfg;
    // No shadow-filter decision on an object; static ones (promoted into SLAM) elsewhere.
    if (cfg == "imm7-shadow.ini")
    {
      const auto res = eval::classificationAgainstMasks(eval::readClassificationsCsv(out + "/classifications.csv"), maskAt, 1);
      EXPECT_EQ(res.confusion.trulyDynamic(), 0u);
      EXPECT_GT(res.confusion.trulyStatic(), 10u);
    }
  }
  // Without the masks the same data gives decisions on the boxes (the classifier's work).
  const std::string out = outDir("noexcl-imm7-shadow");
  ASSERT_EQ(runApp({sourceDir() + "/ini/imm7-shadow.ini", data, "--out", out}), 0);
  const auto res = eval::classificationAgainstMasks(eval::readClassificationsCsv(out + "/classifications.csv"), maskAt, 1);
  EXPECT_GT(res.confusion.trulyDynamic(), 0u);
  std::printf("seed 7 with the moving objects disabled (Fig. 5(a)): IMM %.3f %% of path, full system %.3f %%\n",
              100 * ate["imm7.ini"], 100 * ate["imm7-shadow.ini"]);
  // Measured: IMM 1.097 %, full system 1.068 % of path (0.804 % before the first map's probation:
  // on this one seed it costs; over 40 hold-out seeds the full system's
  // static-world median gains, doc/shadow.md "Movers in the map"); limits ~1.2x.
  EXPECT_LE(ate["imm7.ini"], 0.0131);
  EXPECT_LE(ate["imm7-shadow.ini"], 0.0128);
}

TEST(ShadowSystem, RealVideoWithPastedMovingObjects)
{
  // Real camera motion, background, noise and blur; moving objects cut from another real sequence
  // pasted in with imm-composite, their masks the truth (share/experiments/composite-real.sh, doc/shadow.md).
  // Single runs of one composite are fragile (a 2 % change of the object's size can turn a 0.1 %
  // deviation into 2 %), so each sequence is tested over five small variations of the object's path
  // and size: pooled decisions, mean (testseq, against the IMM without shadow filter on the same
  // composites) and median (visp_rbt, against the clean run) errors.
  if (!haveSharedData("monoslam_testseq") || !haveSharedData("visp_rbt"))
    GTEST_SKIP() << "../shared/data/monoslam_testseq or visp_rbt is absent";
  const auto object = [](const std::string& image, int x, int y, int w, int h, double s0, double s1, Vec2 from, Vec2 to,
                         std::size_t first, std::size_t last, double amp, double period) {
    sim::TCompositeObject o;
    o.image = image;
    o.cropX = x, o.cropY = y, o.cropW = w, o.cropH = h;
    o.scaleFirst = s0, o.scaleLast = s1;
    o.from = from, o.to = to;
    o.firstFrame = first, o.lastFrame = last;
    o.waveAmplitudePx = amp, o.wavePeriodFrames = period;
    return o;
  };
  // Makes a composite folder (fresh) from a shared data set.
  const auto makeComposite = [](const std::string& src, const std::string& name, const std::vector<sim::TCompositeObject>& objs) {
    const auto folder = outDir(name);
    EXPECT_GT(sim::compositeMovingObjects(sharedData(src), folder, objs).objectFrames, 0u);
    return folder;
  };
  // Runs a config on a composite folder; returns the output folder and, when `pooled` is given, adds
  // the decisions scored against the folder's masks.
  const auto runOn = [](const std::string& cfg, const std::string& folder, eval::TConfusionMatrix* pooled,
                        app::TRunSummary* s) {
    const auto out = outDir(std::filesystem::path(folder).filename().string() + "_" + cfg);
    EXPECT_EQ(runApp({sourceDir() + "/ini/" + cfg + ".ini", folder, "--out", out}, s), 0);
    if (pooled)
    {
      const eval::TConfusionMatrix c =
          eval::classificationAgainstMaskFolder(eval::readClassificationsCsv(out + "/classifications.csv"), folder, 1).confusion;
      pooled->staticAsStatic += c.staticAsStatic, pooled->staticAsDynamic += c.staticAsDynamic;
      pooled->dynamicAsStatic += c.dynamicAsStatic, pooled->dynamicAsDynamic += c.dynamicAsDynamic;
    }
    return out;
  };
  const auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };

  // monoslam_testseq (no ground truth): two passes of a large cut-out (20 % of the image on average,
  // up to 43 %); the reference is the full system's run on the clean sequence.
  const std::string visp = sharedData("visp_rbt") + "/rgb/color_image_0050.png";
  const auto outClean = outDir("composite_ts_clean");
  ASSERT_EQ(runApp({sourceDir() + "/ini/imm7-shadow.ini", sharedData("monoslam_testseq"), "--out", outClean}),
            0);
  const core::TTrajectory ref = core::readTumTrajectory(outClean + "/trajectory.txt");
  const std::vector<std::array<double, 3>> tsVariants{{0.45, 30, 60}, {0.44, 30, 60}, {0.46, 30, 60}, {0.45, 28, 60}, {0.45, 30, 56}};
  eval::TConfusionMatrix tsPooled;
  std::vector<double> deviations, deviationsNoShadow;
  for (std::size_t i = 0; i < tsVariants.size(); ++i)
  {
    const auto& [scale, amp, period] = tsVariants[i];
    const std::vector<sim::TCompositeObject> objs{
        object(visp, 170, 140, 400, 280, scale, scale, Vec2(-100, 120), Vec2(420, 120), 100, 400, amp, period),
        object(visp, 170, 140, 400, 280, 0.5, 0.7, Vec2(420, 100), Vec2(-100, 140), 600, 900, amp, period)};
    const auto folder = makeComposite("monoslam_testseq", "composite_ts" + std::to_string(i), objs);
    for (const bool shadow : {true, false})
    {
      const auto out = runOn(shadow ? "imm7-shadow" : "imm7", folder, shadow ? &tsPooled : nullptr, nullptr);
      const core::TTrajectory est = core::readTumTrajectory(out + "/trajectory.txt");
      EXPECT_EQ(est.size(), 1000u) << "variant " << i;
      (shadow ? deviations : deviationsNoShadow).push_back(eval::computeAte(est, ref).rmseOverPath);
    }
    std::printf("testseq + pasted objects, variant %zu: deviation from the clean run %.3f %% of path (IMM without shadow "
                "filter %.3f %%)\n",
                i, 100 * deviations.back(), 100 * deviationsNoShadow.back());
  }
  const auto mean = [](const std::vector<double>& v) { return std::accumulate(v.begin(), v.end(), 0.0) / v.size(); };
  std::printf("testseq + pasted objects, 5 variants: mean deviation %.3f %% of path (median %.3f %%), IMM without shadow "
              "filter %.3f %% (median %.3f %%); moving->static %zu/%zu, static->dynamic %zu/%zu\n",
              100 * mean(deviations), 100 * median(deviations), 100 * mean(deviationsNoShadow),
              100 * median(deviationsNoShadow), tsPooled.dynamicAsStatic, tsPooled.trulyDynamic(), tsPooled.staticAsDynamic,
              tsPooled.trulyStatic());
  // Measured 2026-11-27: full system 0.346 2.410 1.366 0.189 2.182 % (mean 1.299 %); without the
  // shadow filter 2.087 2.297 1.571 1.262 2.194 % (mean 1.882 %); moving->static 1 of 363, static->dynamic
  // 643 of 1155. The claim (paper 2, Fig. 5): the shadow filter keeps the objects out of the estimate;
  // it does so clearly in 2 of 5 variations. With watched features (the default since): 1.684 0.150
  // 0.122 0.157 2.393 % (mean 0.907 %), without the shadow filter mean 1.738 %; moving->static 3 of 450,
  // static->dynamic 531 of 1325. These are single draws of a chaotic run (variants 0 and 4 lose the map
  // while the cut-out covers it): over RANSAC seeds 1-9 ([slam] seed) the 45 runs give 8 deviations
  // above 1 % with watched features and 6 without, moving->static 11 of 4409 and 8 of 4071. Limits ~1.2x
  // the measured figures.
  EXPECT_LE(mean(deviations), 0.75 * mean(deviationsNoShadow));
  EXPECT_LE(mean(deviations), 0.0156);
  EXPECT_GE(tsPooled.trulyDynamic(), 302u);
  EXPECT_LE(tsPooled.movingAsStaticRate(), 0.008);
  EXPECT_LE(tsPooled.staticAsDynamicRate(), 0.67);

  // visp_rbt (AprilTag ground truth): a desk cut-out crossing the whole image (13 % on average).
  const std::string desk = sharedData("monoslam_testseq") + "/rgb/000500.png";
  app::TRunSummary clean;
  ASSERT_EQ(runApp({sourceDir() + "/ini/imm7-shadow.ini", sharedData("visp_rbt"), "--out", outDir("composite_visp_clean")},
                   &clean),
            0);
  ASSERT_TRUE(clean.ate);
  const std::vector<std::array<double, 2>> viVariants{{1.0, 30}, {0.98, 30}, {1.02, 30}, {1.0, 29}, {1.0, 31}};
  eval::TConfusionMatrix viPooled;
  std::vector<double> ates;
  for (std::size_t i = 0; i < viVariants.size(); ++i)
  {
    app::TRunSummary s;
    runOn("imm7-shadow",
          makeComposite("visp_rbt", "composite_visp" + std::to_string(i),
                        {object(desk, 0, 0, 320, 240, viVariants[i][0], viVariants[i][0], Vec2(-160, 240), Vec2(800, 240),
                                0, 98, viVariants[i][1], 50)}),
          &viPooled, &s);
    ASSERT_TRUE(s.ate);
    ates.push_back(s.ate->rmseOverPath);
  }
  std::printf("visp_rbt + pasted object, 5 variants: median ATE %.3f %% of path (%.3f-%.3f) vs %.3f %% on the clean "
              "sequence; moving->static %zu/%zu, static->dynamic %zu/%zu\n",
              100 * median(ates), 100 * *std::min_element(ates.begin(), ates.end()),
              100 * *std::max_element(ates.begin(), ates.end()), 100 * clean.ate->rmseOverPath, viPooled.dynamicAsStatic,
              viPooled.trulyDynamic(), viPooled.staticAsDynamic, viPooled.trulyStatic());
  // Measured 2026-11-27: median 1.986 % (1.816-2.332) vs 1.938 % on the clean sequence (ratio 1.02);
  // the clean sequence itself gives 1.88-3.05 % over start-up variations (doc/shadow.md); moving->static
  // 0 of 144 (static->dynamic 147 of 154: the desk's background corners mix both). With the handling of
  // movers outside the paper's assumptions (doc/shadow.md, "Movers in the map"): median 2.193 %
  // (1.807-3.003) vs 1.934 % clean (ratio 1.13), moving->static 0 of 124. With watched features (the
  // default since): median 2.203 % (1.929-2.593) vs 1.908 % clean (ratio 1.15), moving->static 0 of 106,
  // static->dynamic 80 of 218. Limits ~1.2x.
  EXPECT_LE(median(ates), 1.36 * clean.ate->rmseOverPath);
  EXPECT_LE(median(ates), 0.0263);
  EXPECT_GE(viPooled.trulyDynamic(), 88u);
  EXPECT_LE(viPooled.movingAsStaticRate(), 0.01);
}

namespace
{
/** The folder of Debian's opencv-doc package (its example videos), or "" when it is not installed.
 * IMMSLAM_OPENCV_DOC overrides /usr/share/doc/opencv-doc. */
std::string opencvDocDir()
{
  const char* env = std::getenv("IMMSLAM_OPENCV_DOC");
  const std::string d = env && *env ? env : "/usr/share/doc/opencv-doc";
  return std::filesystem::exists(d + "/opencv4/html/box.mp4.gz") && std::filesystem::exists(d + "/examples/data/vtest.avi")
             ? d
             : std::string();
}

/** gunzip src -> dst. */
bool gunzipFile(const std::string& src, const std::string& dst)
{
  std::filesystem::create_directories(std::filesystem::path(dst).parent_path());
  gzFile in = gzopen(src.c_str(), "rb");
  if (!in) return false;
  std::ofstream out(dst, std::ios::binary);
  char buf[1 << 16];
  int n = 0;
  while ((n = gzread(in, buf, sizeof(buf))) > 0) out.write(buf, n);
  gzclose(in);
  return n == 0 && static_cast<bool>(out);
}

/** A real video of a still camera turned into a dataset folder by imm-rotate (rotation amplitudes in
 * degrees; 0,0,0 keeps the camera at rest), with a guessed pinhole calibration of focal length f. */
std::string realVideoFolder(const std::string& video, const std::string& name, int w, int h, double f, double pan, double tilt,
                            double roll, std::size_t frames)
{
  const std::string folder = outDir(name);
  std::filesystem::create_directories(folder + "_calib");
  const std::string calib = folder + "_calib/calib.txt";
  std::ofstream(calib) << "pinhole " << w << ' ' << h << ' ' << f << ' ' << f << ' ' << 0.5 * (w - 1) << ' ' << 0.5 * (h - 1)
                       << '\n';
  sim::TRotatedViewOptions o;
  o.calibFile = calib;
  o.panDeg = pan, o.tiltDeg = tilt, o.rollDeg = roll;
  if (pan == 0 && tilt == 0 && roll == 0) o.width = w, o.height = h;
  o.maxFrames = frames;
  EXPECT_GT(sim::rotateStillVideo(video, folder, o).frames, 0u);
  return folder;
}

/** What a run on such a folder measured. */
struct TRealVideoRun
{
  double rotationRmseDeg = 0;  ///< against the known rotation, no alignment
  double segmentation = 0;     ///< motion segmentation accuracy against motion_labels.txt
  eval::TConfusionMatrix decisions;  ///< shadow-filter decisions against the masks
};

/** \param watch [system] watch_features, or -1 for the config's own (10 by default). */
TRealVideoRun runRealVideo(const std::string& cfg, const std::string& folder, int watch = -1)
{
  const auto out = outDir(std::filesystem::path(folder).filename().string() + "_" + cfg +
                          (watch >= 0 ? "_watch" + std::to_string(watch) : ""));
  std::vector<std::string> args{sourceDir() + "/ini/" + cfg + ".ini", folder, "--out", out};
  if (watch >= 0) args.insert(args.end(), {"--set", "system.watch_features=" + std::to_string(watch)});
  EXPECT_EQ(runApp(args), 0);
  TRealVideoRun r;
  r.rotationRmseDeg = eval::computeAte(core::readTumTrajectory(out + "/trajectory.txt"),
                                       core::readTumTrajectory(folder + "/groundtruth.txt"), eval::EAlignment::None)
                          .rotationRmseDeg;
  r.segmentation = eval::segmentationAccuracy(eval::readModelProbabilitiesCsv(out + "/model_probabilities.csv"),
                                              eval::readMotionLabels(folder + "/motion_labels.txt"))
                       .accuracy;
  if (std::filesystem::exists(out + "/classifications.csv"))
    r.decisions =
        eval::classificationAgainstMaskFolder(eval::readClassificationsCsv(out + "/classifications.csv"), folder, 1).confusion;
  std::printf("%s on %s: rotation RMSE %.3f deg, segmentation %.1f %%, decisions %zu dynamic / %zu static, moving->static "
              "%zu/%zu, static->dynamic %zu/%zu\n",
              cfg.c_str(), folder.c_str(), r.rotationRmseDeg, 100 * r.segmentation,
              r.decisions.staticAsDynamic + r.decisions.dynamicAsDynamic, r.decisions.staticAsStatic + r.decisions.dynamicAsStatic,
              r.decisions.dynamicAsStatic, r.decisions.trulyDynamic(), r.decisions.staticAsDynamic, r.decisions.trulyStatic());
  return r;
}
}  // namespace

TEST(ShadowSystem, RealVideoOfAHandMovingABoxInFrontOfAStillCamera)
{
  // opencv-doc's box.mp4: a hand moves a textured box (a fifth to a third of the image) in front of a
  // camera on a tripod (checked: background patches stay within 1 px over the whole video), the box
  // in view from the first frame. Truth: the camera is at rest; masks/ mark what moves
  // (share/experiments/real-videos.sh and doc/shadow.md give every config's figures).
  const std::string doc = opencvDocDir();
  if (doc.empty()) GTEST_SKIP() << "opencv-doc is not installed (apt-get install opencv-doc)";
  const std::string video = outDir("realvideo_box_src") + ".mp4";
  ASSERT_TRUE(gunzipFile(doc + "/opencv4/html/box.mp4.gz", video));
  const std::string folder = realVideoFolder(video, "realvideo_box", 640, 480, 560, 0, 0, 0, 0);
  const TRealVideoRun full = runRealVideo("imm7-shadow", folder);
  const TRealVideoRun notWatching = runRealVideo("imm7-shadow", folder, 0);
  const TRealVideoRun noShadow = runRealVideo("imm7", folder);
  const TRealVideoRun single = runRealVideo("single", folder);
  {
    // The video given directly as INPUT is the same stream as the folder imm-rotate wrote at rest
    // (identity remap, lossless PNG, the container's frame rate): the same trajectory, to the byte.
    const auto out = outDir("realvideo_box_direct");
    ASSERT_EQ(runApp({sourceDir() + "/ini/imm7-shadow.ini", video, "--calib", folder + "_calib/calib.txt", "--out", out}),
              0);
    const std::string direct = readFile(out + "/trajectory.txt");
    EXPECT_GT(direct.size(), 1000u);
    EXPECT_EQ(direct, readFile(folder + "_imm7-shadow/trajectory.txt"));  // runRealVideo's output folder
  }
  // Measured: full system (watched features, the default) rotation RMSE 2.12 deg, segmentation 84.8 %,
  // 232 dynamic and 42 static decisions, moving->static 18 of 241 against imm-rotate's MOG2 masks
  // (36 of 262 before static decisions waited among dynamic features, amongDynamic in CShadowFilter.cpp;
  // 22 of 244 before they waited where motion was seen lately, nearRecentMotion), which also mark the
  // box while the hand holds it still (for less than half of the video), when a static decision is
  // what the test should give; without watched features 1.93 deg, 107 / 29 decisions, moving->static
  // 16 of 116. IMM without shadow filter 0.28 deg, 27.3 %; single model
  // 34.9 deg (the IMM without shadow filter explains the box with general motion and a map at
  // infinity). A dynamic decision then came to need a track that follows one point (min_point_ncc):
  // 184 decisions on what moves (170 dynamic, moving->static 14 of 184), 7 of 25 on the background
  // dynamic (13 of 30 before), 2.00 deg; without watched features 95 (13 static), 1.88 deg. Since a
  // pending feature's views start again after a miss (CShadowFilter::updateFeature): 152 decisions on
  // what moves, 140 dynamic (moving->static 12 of 152), 0 of 11 on the background dynamic, 1.99 deg;
  // without watched features 87 (12 static), 1.87 deg. Limits ~1.2x.
  EXPECT_LT(full.rotationRmseDeg, 2.53);
  EXPECT_GT(single.rotationRmseDeg, 10.0) << "the single model follows the box: the test must see that failure";
  EXPECT_GT(full.segmentation, 0.768);
  EXPECT_GT(full.segmentation, noShadow.segmentation + 0.3);
  EXPECT_GE(full.decisions.trulyDynamic(), 127u);
  EXPECT_LE(full.decisions.movingAsStaticRate(), 0.108);
  EXPECT_LT(notWatching.rotationRmseDeg, 2.31);
  EXPECT_GE(notWatching.decisions.trulyDynamic(), 79u);
  EXPECT_LE(notWatching.decisions.movingAsStaticRate(), 0.17);
}

TEST(ShadowSystem, RealVideoOfPeopleWalkingSeenByARotatingCamera)
{
  // opencv-doc's vtest.avi (people walking across a courtyard, a still camera) turned by imm-rotate
  // into the video of a camera panning, tilting and rolling by 3 / 2 / 1.5 degrees.
  const std::string doc = opencvDocDir();
  if (doc.empty()) GTEST_SKIP() << "opencv-doc is not installed (apt-get install opencv-doc)";
  const std::string folder =
      realVideoFolder(doc + "/examples/data/vtest.avi", "realvideo_vtest", 768, 576, 700, 3, 2, 1.5, 300);
  const TRealVideoRun full = runRealVideo("imm7-shadow", folder);
  const TRealVideoRun notWatching = runRealVideo("imm7-shadow", folder, 0);
  const TRealVideoRun single = runRealVideo("single", folder);
  // Measured over 300 frames: full system 0.009 deg, segmentation 100 %; single model 0.140 deg.
  EXPECT_LT(full.rotationRmseDeg, 0.011);
  EXPECT_LT(full.rotationRmseDeg, single.rotationRmseDeg);
  EXPECT_GT(full.segmentation, 0.99);
  // The watched features (the default) let the shadow filter see the people while the map is
  // complete: 15 decisions on people (all dynamic), 1 of 54 on the courtyard dynamic, against MOG2
  // masks (22, 20 dynamic, and 3 of 98 before the static decisions of new features waited for a track
  // of 30 frames while the camera does not translate: fewer decisions, as a watched feature holds its
  // slot longer; over the whole video 54 decisions on people, 1 static, against 85 and 11.8 %,
  // doc/shadow.md). Without them 26 decisions, all but one on the first map's probation copies.
  // Since a dynamic decision needs a track that follows one point (min_point_ncc; a walking person's
  // patches deform): 9 decisions on people, all dynamic, 1 of 54 on the courtyard. Since a pending
  // feature's views start again after a miss (a walking person's features are missed often): 6 on
  // people, all dynamic. Limits ~1.2x.
  EXPECT_GE(full.decisions.trulyDynamic(), 5u);
  EXPECT_LE(full.decisions.movingAsStaticRate(), 0.095);
  EXPECT_LE(full.decisions.staticAsDynamicRate(), 0.041);
  EXPECT_LE(notWatching.decisions.dynamicAsStatic, 0u) << "nothing moving enters the map";
}

TEST(ShadowSystem, RealHandPastedIntoARealHandHeldVideo)
{
  // What moves in opencv-doc's box.mp4 (an arm and a hand moving a box, cut out by the masks imm-rotate
  // writes for the still camera) pasted with imm-composite into monoslam_testseq (a real hand-held
  // camera): a real hand in front of a real moving camera, with the pasted pixels as the truth and the
  // full system's run on the clean sequence as the reference (doc/shadow.md).
  const std::string doc = opencvDocDir();
  if (doc.empty()) GTEST_SKIP() << "opencv-doc is not installed (apt-get install opencv-doc)";
  if (!haveSharedData("monoslam_testseq")) GTEST_SKIP() << "../shared/data/monoslam_testseq is absent";
  const std::string video = outDir("realhand_box_src") + ".mp4";
  ASSERT_TRUE(gunzipFile(doc + "/opencv4/html/box.mp4.gz", video));
  const std::string hand = realVideoFolder(video, "realhand_box", 640, 480, 560, 0, 0, 0, 0);
  const auto outClean = outDir("realhand_ts_clean");
  ASSERT_EQ(runApp({sourceDir() + "/ini/imm7-shadow.ini", sharedData("monoslam_testseq"), "--out", outClean}),
            0);
  const core::TTrajectory ref = core::readTumTrajectory(outClean + "/trajectory.txt");
  struct TVariant
  {
    std::size_t first, last, videoStart;
    double scale;
  };
  const std::vector<TVariant> variants{{100, 554, 0, 0.5}, {300, 754, 0, 0.45}, {500, 954, 0, 0.55}};
  std::map<std::string, std::vector<double>> deviation;
  eval::TConfusionMatrix pooled;
  for (std::size_t v = 0; v < variants.size(); ++v)
  {
    sim::TCompositeObject o;
    o.video = hand;
    o.firstFrame = variants[v].first, o.lastFrame = variants[v].last, o.videoStart = variants[v].videoStart;
    o.scaleFirst = o.scaleLast = variants[v].scale;
    const auto folder = outDir("realhand_ts" + std::to_string(v));
    ASSERT_GT(sim::compositeMovingObjects(sharedData("monoslam_testseq"), folder, {o}).objectFrames, 400u);
    for (const std::string cfg : {"imm7-shadow", "imm7", "single"})
    {
      const auto out = outDir("realhand_ts" + std::to_string(v) + "_" + cfg);
      ASSERT_EQ(runApp({sourceDir() + "/ini/" + cfg + ".ini", folder, "--out", out}), 0);
      deviation[cfg].push_back(eval::computeAte(core::readTumTrajectory(out + "/trajectory.txt"), ref).rmseOverPath);
      if (cfg == "imm7-shadow")
      {
        const auto c = eval::classificationAgainstMaskFolder(eval::readClassificationsCsv(out + "/classifications.csv"), folder, 1)
                           .confusion;
        pooled.staticAsStatic += c.staticAsStatic, pooled.staticAsDynamic += c.staticAsDynamic;
        pooled.dynamicAsStatic += c.dynamicAsStatic, pooled.dynamicAsDynamic += c.dynamicAsDynamic;
      }
      std::printf("real hand in testseq, variant %zu, %s: %.3f %% of path from the clean run\n", v, cfg.c_str(),
                  100 * deviation[cfg].back());
    }
  }
  const auto mean = [](const std::vector<double>& x) { return std::accumulate(x.begin(), x.end(), 0.0) / x.size(); };
  std::printf("real hand in testseq: mean deviation full system %.3f %%, IMM without shadow filter %.3f %%, single model "
              "%.3f %%; moving->static %zu/%zu, static->dynamic %zu/%zu\n",
              100 * mean(deviation["imm7-shadow"]), 100 * mean(deviation["imm7"]), 100 * mean(deviation["single"]),
              pooled.dynamicAsStatic, pooled.trulyDynamic(), pooled.staticAsDynamic, pooled.trulyStatic());
  // Measured (the hand and the box cut out by imm-rotate's MOG2 masks): full system 0.102 / 0.090 /
  // 0.101 % (mean 0.098 %; IMM without shadow filter 0.914 / 0.578 / 1.301 %, single model 0.968 /
  // 0.699 / 0.231 %); none of 66 decisions on the hand and the box static; static->dynamic 26 of 290.
  // With the first map's probation and the handover of mapped movers: mean 0.138 %, 0 of 146 on the
  // hand and the box static, static->dynamic 66 of 525 (the probation copies add decisions). With
  // watched features (the default since): mean 0.076 % (IMM without shadow filter 0.983 %, single
  // model 0.650 %), 2 of 155 on the hand and the box static (the masks also mark the box while the
  // hand holds it still), static->dynamic 52 of 540. With static decisions waiting for a track of 30
  // frames while the camera does not translate: 0.805 / 0.060 / 0.149 % (mean 0.338 %; IMM without
  // shadow filter 0.967 %, single model 0.641 %), 0 of 144 on the hand and the box static,
  // static->dynamic 95 of 566. Variant 0 deviates on every RANSAC seed tried (0.80 / 0.30 / 0.38 % for
  // --set slam.seed=1..3, against 0.10 / 0.10 / 0.09 % before): its first map's probation copies are
  // confirmed at the camera's first translation instead of at frame 10, and the run takes another
  // course (experiments/shadow-filter.md). Limits ~1.2x.
  EXPECT_LE(mean(deviation["imm7-shadow"]), 0.5 * mean(deviation["imm7"]));
  EXPECT_LE(mean(deviation["imm7-shadow"]), mean(deviation["single"]));
  EXPECT_LT(mean(deviation["imm7-shadow"]), 0.0041);
  EXPECT_GE(pooled.trulyDynamic(), 55u);
  EXPECT_LE(pooled.movingAsStaticRate(), 0.0155);
  EXPECT_LE(pooled.staticAsDynamicRate(), 0.202);
}
