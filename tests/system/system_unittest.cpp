/* End-to-end accuracy and behaviour of the application on rendered and real sequences. */
#include "test_helpers.h"

#include <immslam/core/TTrajectory.h>
#include <immslam/camera/CCameraModel.h>
#include <immslam/eval/ate.h>
#include <immslam/refine/bundle_adjust.h>
#include <immslam/eval/relative_nees.h>
#include <immslam/eval/rpe.h>
#include <immslam/sim/CSimulator.h>
#include <immslam/sim/TScenario.h>
#include <immslam/eval/search_nis.h>
#include <immslam/eval/statistics.h>
#include <immslam/viz/scene.h>

#include <mrpt/opengl/CSetOfLines.h>

#include <algorithm>
#include <fstream>
#include <sstream>

#include <cmath>
#include <filesystem>

using namespace immslam;
using namespace immslam::test;

TEST(SystemSynthetic, HandheldSingleModelAteWithinOnePercentOfPath)
{
  // handheld.ini (seed 7), single model. Measured 2026-11-27 (imm-render --seed S + imm-monoslam):
  // 0.77 % of path on seed 7 (this test), 0.79 % on 11, 0.57 % on 23. Limit 1.2x seed 7's.
  app::TRunSummary s;
  ASSERT_EQ(runApp({sourceDir() + "/ini/single.ini", "--out", outDir("handheld_single"), "--set",
                    "input.scenario=scenarios/handheld.ini"},
                   &s),
            0);
  ASSERT_TRUE(s.ate.has_value());
  std::printf("handheld single: ATE %.4f = %.3f %% of path (%zu poses)\n", s.ate->rmse, 100 * s.ate->rmseOverPath,
              s.ate->nPairs);
  EXPECT_EQ(s.framesProcessed, s.ate->nPairs);
  EXPECT_LE(s.ate->rmseOverPath, 0.0092);
}

TEST(SystemSynthetic, FisheyeLensDefaultConfigAteWithinOnePercentOfPath)
{
  // The hand-held path through the TUM-VI fisheye lens (190 degrees along the diagonal, black corners),
  // with the default configuration: the camera model is used end to end (search, warps, inverse depth,
  // shadow filter, relocalisation) and the lens mask keeps new features inside the image circle.
  // ATE measured 2026-11-27: 0.43 % of path on seed 7 (this test), 0.20 % on 11, 0.27 % on 23; limit
  // 1.2x seed 7's.
  app::TRunSummary s;
  const std::string out = outDir("handheld_fisheye");
  ASSERT_EQ(runApp({sourceDir() + "/ini/imm7-shadow.ini", "--out", out, "--set",
                    "input.scenario=scenarios/handheld-fisheye.ini", "--set",
                    "output.search_log=true"},
                   &s),
            0);
  ASSERT_TRUE(s.ate.has_value());
  std::printf("handheld fisheye, full system: ATE %.4f = %.3f %% of path (%zu poses)\n", s.ate->rmse,
              100 * s.ate->rmseOverPath, s.ate->nPairs);
  EXPECT_EQ(s.framesProcessed, s.ate->nPairs);
  EXPECT_LE(s.ate->rmseOverPath, 0.0051);
  // Every measurement lies inside the image circle (radius f * 90 degrees about the principal point).
  const auto rows = readCsv(out + "/searches.csv");
  ASSERT_GT(rows.size(), 1000u);
  const auto& head = rows.front();
  const auto col = [&](const std::string& name) { return std::find(head.begin(), head.end(), name) - head.begin(); };
  const std::size_t cu = col("z_u"), cv = col("z_v"), cf = col("found");
  ASSERT_LT(cf, head.size());
  std::size_t found = 0;
  for (std::size_t i = 1; i < rows.size(); ++i)
  {
    if (rows[i][cf] != "1") continue;
    ++found;
    const double r = std::hypot(std::stod(rows[i][cu]) - 254.93, std::stod(rows[i][cv]) - 256.90);
    EXPECT_LT(r, 190.97 * M_PI / 2) << "row " << i;
  }
  EXPECT_GT(found, 1000u);
}

TEST(SystemRealData, VispRbtAteWithinThreePercentOfPath)
{
  if (!haveSharedData("visp_rbt")) GTEST_SKIP() << "../shared/data/visp_rbt is absent";
  app::TRunSummary s;
  ASSERT_EQ(runApp({sourceDir() + "/ini/single.ini", sharedData("visp_rbt"), "--out", outDir("visp_single")},
                   &s),
            0);
  ASSERT_TRUE(s.ate.has_value());
  std::printf("visp_rbt single: ATE %.4f = %.3f %% of path\n", s.ate->rmse, 100 * s.ate->rmseOverPath);
  EXPECT_EQ(s.framesProcessed, 99u);
  // Measured 1.898 % (2026-11-27; one real sequence): limit 1.2x. (The AprilTag poses themselves lie
  // 1.75 % of path from a bundle adjustment of the images: see the test below.)
  EXPECT_LE(s.ate->rmseOverPath, 0.0228);
}

TEST(SystemRealData, MonoslamTestseqTrackedEndToEndWithoutKnownTarget)
{
  // The single model over the 1000 real frames (no ground truth): never lost, and the trajectory
  // explains the run's own matches: the features triangulated from the estimated poses reproject onto
  // their measurements (a wrong trajectory cannot place one point per feature that fits every view).
  if (!haveSharedData("monoslam_testseq")) GTEST_SKIP() << "../shared/data/monoslam_testseq is absent";
  app::TRunSummary s;
  const auto out = outDir("testseq_single");
  ASSERT_EQ(runApp({sourceDir() + "/ini/single.ini", sharedData("monoslam_testseq"), "--out", out, "--set", "output.search_log=true"},
                   &s),
            0);
  EXPECT_EQ(s.framesProcessed, 1000u);
  const auto rows = readCsv(out + "/frame_stats.csv");
  ASSERT_EQ(rows.size(), 1001u);
  // Never lost: measurements are used in every frame after the first.
  int minMatched = 1 << 30;
  for (std::size_t i = 2; i < rows.size(); ++i) minMatched = std::min(minMatched, std::stoi(rows[i][3]));
  const auto cam = camera::loadCalibFile(sharedData("monoslam_testseq") + "/calib.txt");
  const auto st = refine::reprojectionStats(refine::makeBundleProblem(eval::readSearchesCsv(out + "/searches.csv"),
                                                                  core::readTumTrajectory(out + "/trajectory.txt"),
                                                                  *cam, 1e-4, 8));
  std::printf("testseq single: median matched %.0f, min matched %d, final map %d; the estimate's poses leave %zu of %zu "
              "features above 2 px, RMS %.3f px over %zu poses\n",
              s.medianMatched, minMatched, s.finalMapSize, st.featuresAbove, st.nFeatures, st.rmsPx, st.nPoses);
  // Limits at ~1.2x the measured figures of this deterministic run (2026-11-27): min matched 14,
  // median 23; 999 poses, RMS 0.948 px, 3 of 170 features above 2 px.
  EXPECT_GE(minMatched, 11);
  EXPECT_GE(s.medianMatched, 19);
  EXPECT_GE(st.nPoses, 990u);
  EXPECT_LT(st.rmsPx, 1.14);
  EXPECT_LE(st.featuresAbove, 4u);
}

namespace
{
/** A bundle adjustment of a run's own measurements (searches.csv) started from `start`. */
refine::TBundleProblem refinedFrom(const std::string& out, const core::TTrajectory& start, const std::string& calib,
                                 refine::TReprojectionStats* before = nullptr)
{
  const auto cam = camera::loadCalibFile(calib);
  refine::TBundleProblem p = refine::makeBundleProblem(eval::readSearchesCsv(out + "/searches.csv"), start, *cam, 1e-4, 8);
  if (before) *before = refine::reprojectionStats(p);
  const auto r = refine::bundleAdjust(p);
  EXPECT_TRUE(r.converged);
  EXPECT_LT(refine::reprojectionStats(p).rmsPx, 1.0);
  return p;
}

/** A run of CONFIG on a shared sequence with its searches logged, and the adjustment of its matches. */
struct TRefinedRun
{
  core::TTrajectory est;
  refine::TBundleProblem ba;
};
TRefinedRun runAndRefine(const std::string& config, const std::string& data, const std::string& name)
{
  const auto out = outDir(name);
  EXPECT_EQ(runApp({sourceDir() + "/ini/" + config, sharedData(data), "--out", out,
                    "--set", "output.search_log=true"}),
            0);
  TRefinedRun r;
  r.est = core::readTumTrajectory(out + "/trajectory.txt");
  r.ba = refinedFrom(out, r.est, sharedData(data) + "/calib.txt");
  return r;
}
}  // namespace

TEST(SystemRealData, VispRbtGroundTruthDisagreesWithTheImagesAndTheEstimateAgrees)
{
  // The AprilTag poses of visp_rbt against the images: triangulated from them, the features off the
  // board plane (objects on the table, the wall) miss by pixels, while one rigid trajectory explains
  // every measurement to the matching noise (a bundle adjustment, the same from the AprilTag start and
  // from the SLAM's). That trajectory is ~1.75 % of path from the AprilTag poses and its relative
  // translation directions ~30 deg from theirs; the IMM's estimate is within 1 % of path and a few
  // degrees of it. Measured: GT 22/43 features above 2 px; BA vs GT 1.75 %, 30 deg (10 frames);
  // estimate vs BA 0.63 %, 2.9 deg (0.67 %, 2.2 deg against the adjustment without its outlier
  // pass). (synth19's exact ground truth, below, shows none of this.)
  if (!haveSharedData("visp_rbt")) GTEST_SKIP() << "../shared/data/visp_rbt is absent";
  const auto out = outDir("visp_reprojection");
  ASSERT_EQ(runApp({sourceDir() + "/ini/imm7.ini", sharedData("visp_rbt"), "--out", out,
                    "--set", "output.search_log=true"}),
            0);
  const auto gt = core::readTumTrajectory(sharedData("visp_rbt") + "/groundtruth.txt");
  const auto est = core::readTumTrajectory(out + "/trajectory.txt");
  const std::string calib = sharedData("visp_rbt") + "/calib.txt";
  refine::TReprojectionStats gtStats, estStats;
  const auto fromGt = refinedFrom(out, gt, calib, &gtStats);
  const auto fromEst = refinedFrom(out, est, calib, &estStats);
  const double baVsBa = eval::computeAte(fromEst.poses, fromGt.poses).rmseOverPath;
  const double baVsGt = eval::computeAte(fromGt.poses, gt).rmseOverPath;
  const double estVsBa = eval::computeAte(est, fromGt.poses).rmseOverPath;
  const double dirBaGt = eval::computeRpe(fromGt.poses, gt, 10).directionMedianDeg;
  const double dirEstBa = eval::computeRpe(est, fromGt.poses, 10).directionMedianDeg;
  std::printf("visp_rbt: AprilTag poses leave %zu of %zu features above 2 px (RMS %.2f px); BA from both starts "
              "%.5f %% apart; BA vs AprilTag %.2f %% of path, direction %.1f deg; estimate vs BA %.2f %%, %.1f deg\n",
              gtStats.featuresAbove, gtStats.nFeatures, gtStats.rmsPx, 100 * baVsBa, 100 * baVsGt, dirBaGt,
              100 * estVsBa, dirEstBa);
  EXPECT_GT(gtStats.featuresAbove, gtStats.nFeatures / 4);
  EXPECT_LT(baVsBa, 1e-4);
  EXPECT_GT(baVsGt, 0.012);
  EXPECT_GT(dirBaGt, 15.0);
  // The estimate's figures at ~1.2x the measured ones (0.63 % of path, 2.9 deg).
  EXPECT_LT(estVsBa, 0.0076);
  EXPECT_LT(dirEstBa, 3.5);
}

TEST(SystemRealData, ExactGroundTruthAndLongRealRunAgreeWithTheirMeasurements)
{
  // The control of the test above: synth19's exact poses explain the SLAM's measurements to the
  // matching noise (no feature above 2 px). And monoslam_testseq (no ground
  // truth): the full system's 1000 frames against a bundle adjustment of its own measurements
  // (a self-consistency figure, not an accuracy one).
  if (!haveSharedData("monoslammot_synth19") || !haveSharedData("monoslam_testseq"))
    GTEST_SKIP() << "../shared/data/monoslammot_synth19 or monoslam_testseq is absent";
  {
    const auto out = outDir("synth19_reprojection");
    ASSERT_EQ(runApp({sourceDir() + "/ini/imm7-shadow.ini", sharedData("monoslammot_synth19"), "--out", out, "--set", "output.search_log=true"}),
              0);
    const auto cam = camera::loadCalibFile(sharedData("monoslammot_synth19") + "/calib.txt");
    const auto st = refine::reprojectionStats(
        refine::makeBundleProblem(eval::readSearchesCsv(out + "/searches.csv"),
                                core::readTumTrajectory(sharedData("monoslammot_synth19") + "/groundtruth.txt"), *cam,
                                1e-4, 8));
    std::printf("synth19: ground truth leaves %zu of %zu features above 2 px, RMS %.2f px\n", st.featuresAbove,
                st.nFeatures, st.rmsPx);
    // Measured: 2 of 230 features above 2 px, RMS 0.46 px, with the map as the three-ray test's
    // reference (1 of 232, 0.44 px without it; 0 of 222, 0.40 px before first-map probation and
    // handovers; which of synth19's 48 moving points or mismatches they are has not been established).
    // The same run's ATE 0.44 % of path (0.47 without the map's reference), moving -> static 0 / 31.
    EXPECT_LE(st.featuresAbove, 2u);
    EXPECT_LT(st.rmsPx, 0.53);
  }
  const auto full = runAndRefine("imm7-shadow.ini", "monoslam_testseq", "testseq_reprojection");
  const auto& est = full.est;
  const auto& ba = full.ba;
  const auto ate = eval::computeAte(est, ba.poses);
  std::printf("testseq: estimate vs a bundle adjustment of its measurements: %.3f %% of path, %.2f %% of extent "
              "(%zu poses)\n",
              100 * ate.rmseOverPath, 100 * ate.rmseOverExtent, ate.nPairs);
  EXPECT_GE(ate.nPairs, 990u);
  // Measured: 0.121 % of path, 0.90 % of extent (997 poses; 0.194 % and 1.50 % without the
  // adjustment's outlier pass); limit ~1.2x.
  EXPECT_LT(ate.rmseOverPath, 0.00145);

  // A less circular reference: the adjustment of an independent run's matches (the single model's):
  // how far apart the two adjustments are, and the full system from the single model's.
  const auto baSingle = runAndRefine("single.ini", "monoslam_testseq", "testseq_reprojection_single").ba;
  const auto between = eval::computeAte(ba.poses, baSingle.poses);
  const auto cross = eval::computeAte(est, baSingle.poses);
  std::printf("testseq: adjustments of two runs %.3f %% of path apart; full system vs the single model's adjustment "
              "%.3f %% of path, %.2f %% of extent\n",
              100 * between.rmseOverPath, 100 * cross.rmseOverPath, 100 * cross.rmseOverExtent);
  // Measured: 0.063 % and 0.137 % of path (0.095 % and 0.221 % without the outlier pass); limits
  // ~1.2x.
  EXPECT_LT(between.rmseOverPath, 0.00076);
  EXPECT_LT(cross.rmseOverPath, 0.00165);
}

TEST(SystemOutputs, RefinedTrajectoryOnlyWhenAsked)
{
  // [output] refine_trajectory: trajectory_refined.txt (every frame: the poses that measure >= 6
  // features adjusted, the others between them; in the filter's frame), closer to the truth than the
  // filter's; not written unless asked.
  const std::vector<std::string> base{sourceDir() + "/ini/imm7-shadow.ini", "--frames", "120", "--set",
                                      "input.scenario=scenarios/handheld.ini"};
  auto args = base;
  const auto plain = outDir("refine_off");
  args.insert(args.end(), {"--out", plain});
  ASSERT_EQ(runApp(args), 0);
  EXPECT_FALSE(std::filesystem::exists(plain + "/trajectory_refined.txt"));

  args = base;
  const auto refined = outDir("refine_on");
  args.insert(args.end(), {"--out", refined, "--set", "output.refine_trajectory=true"});
  app::TRunSummary s;
  ASSERT_EQ(runApp(args, &s), 0);
  const auto traj = core::readTumTrajectory(refined + "/trajectory_refined.txt");
  const auto filter = core::readTumTrajectory(refined + "/trajectory.txt");
  ASSERT_EQ(traj.size(), filter.size());
  for (std::size_t i = 0; i < traj.size(); ++i) EXPECT_EQ(traj[i].timestamp, filter[i].timestamp);
  ASSERT_TRUE(s.ate && s.ateRefined);
  std::printf("handheld 120 frames: filter %.3f %%, refined %.3f %% of path (%.2f s)\n", 100 * s.ate->rmseOverPath,
              100 * s.ateRefined->rmseOverPath, s.refineSeconds);
  EXPECT_LT(s.ateRefined->rmseOverPath, s.ate->rmseOverPath);
  // Measured: filter 1.957 %, refined 0.313 % of path (0.451 % without the adjustment's outlier
  // pass and the shadow filter's held-back matches); limits ~1.2x.
  EXPECT_LT(s.ate->rmseOverPath, 0.0235);
  EXPECT_LT(s.ateRefined->rmseOverPath, 0.0038);
  // The filter's own outputs do not change.
  EXPECT_EQ(readFile(plain + "/trajectory.txt"), readFile(refined + "/trajectory.txt"));
}

TEST(SystemOutputs, SmoothedTrajectoryByDefaultAndTheFilterUnchanged)
{
  // [output] smooth_trajectory (on by default): trajectory_smoothed.txt, one pose per processed
  // frame, from the keyframe smoother's thread; its ATE, lag and CPU time in the summary; the
  // filter's own outputs byte-identical to a run without it (smooth_trajectory = false: no file);
  // better than the filter.
  const std::vector<std::string> base{sourceDir() + "/ini/imm7-shadow.ini", "--frames", "120", "--set",
                                      "input.scenario=scenarios/handheld.ini"};
  auto args = base;
  const auto plain = outDir("smooth_off");
  args.insert(args.end(), {"--out", plain, "--set", "output.smooth_trajectory=false"});
  ASSERT_EQ(runApp(args), 0);
  EXPECT_FALSE(std::filesystem::exists(plain + "/trajectory_smoothed.txt"));

  args = base;
  const auto smoothed = outDir("smooth_on");
  args.insert(args.end(), {"--out", smoothed});
  app::TRunSummary s;
  ASSERT_EQ(runApp(args, &s), 0);
  const auto traj = core::readTumTrajectory(smoothed + "/trajectory_smoothed.txt");
  const auto filter = core::readTumTrajectory(smoothed + "/trajectory.txt");
  ASSERT_EQ(traj.size(), filter.size());
  for (std::size_t i = 0; i < traj.size(); ++i) EXPECT_EQ(traj[i].timestamp, filter[i].timestamp);
  ASSERT_TRUE(s.ate && s.ateSmoothed);
  std::printf("handheld 120 frames: filter %.3f %%, smoothed %.3f %% of path; lag median %.0f, max %.0f frames; "
              "smoother CPU %.2f s\n",
              100 * s.ate->rmseOverPath, 100 * s.ateSmoothed->rmseOverPath, s.smoothMedianLagFrames,
              s.smoothMaxLagFrames, s.smoothCpuSeconds);
  // A recorded input waits for the smoother (never skips a window): the result does not depend on
  // the machine's load. On this path it halves the filter's error (doc/estimator.md).
  EXPECT_LT(s.ateSmoothed->rmseOverPath, 0.5 * s.ate->rmseOverPath);
  EXPECT_EQ(readFile(plain + "/trajectory.txt"), readFile(smoothed + "/trajectory.txt"));
  EXPECT_EQ(readFile(plain + "/model_probabilities.csv"), readFile(smoothed + "/model_probabilities.csv"));
  // The scene draws the smoothed trajectory beside the filter's (a run without smoothing: none).
  const auto scene = viz::loadSceneFile(smoothed + "/scene.3Dscene");
  const auto line = std::dynamic_pointer_cast<mrpt::opengl::CSetOfLines>(viz::findObject(*scene, "smoothed_trajectory"));
  ASSERT_TRUE(line);
  EXPECT_EQ(line->getLineCount(), traj.size() - 1);
  EXPECT_FALSE(viz::findObject(*viz::loadSceneFile(plain + "/scene.3Dscene"), "smoothed_trajectory"));
}

TEST(SystemOutputs, ContractFilesAndDeterminism)
{
  // Two runs of the same input and config: the estimates are byte-identical (timings aside).
  const std::vector<std::string> base{sourceDir() + "/ini/imm7.ini", "--frames", "60", "--set",
                                      "input.scenario=scenarios/paper.ini"};
  const auto a = outDir("determinism_a"), b = outDir("determinism_b");
  auto args = base;
  args.insert(args.end(), {"--out", a});
  ASSERT_EQ(runApp(args), 0);
  args = base;
  args.insert(args.end(), {"--out", b});
  ASSERT_EQ(runApp(args), 0);
  for (const auto* f : {"trajectory.txt", "model_probabilities.csv", "map.csv"})
    EXPECT_EQ(readFile(a + "/" + f), readFile(b + "/" + f)) << f;

  const auto probs = readCsv(a + "/model_probabilities.csv");
  ASSERT_EQ(probs.size(), 61u);
  EXPECT_EQ(probs[0][0], "timestamp");
  EXPECT_EQ(probs[0].size(), 8u);
  for (std::size_t i = 1; i < probs.size(); ++i)
  {
    double sum = 0;
    for (std::size_t j = 1; j < probs[i].size(); ++j) sum += std::stod(probs[i][j]);
    EXPECT_NEAR(sum, 1.0, 1e-6);
    EXPECT_EQ(probs[i][0].substr(probs[i][0].find('.') + 1).size(), 6u);  // >= 6 decimals
  }
  const auto stats = readCsv(a + "/frame_stats.csv");
  const std::vector<std::string> head{"timestamp", "n_map", "n_predicted", "n_matched", "n_rejected",
                                      "mean_search_area_px2", "n_depth_known", "time_ms"};
  ASSERT_GE(stats[0].size(), head.size());
  for (std::size_t j = 0; j < head.size(); ++j) EXPECT_EQ(stats[0][j], head[j]);
  const auto map = readCsv(a + "/map.csv");
  EXPECT_EQ(map[0][0], "feature_id");
  EXPECT_EQ(map[0][4], "depth_known");
  EXPECT_TRUE(std::filesystem::exists(a + "/scene.3Dscene"));
  EXPECT_TRUE(std::filesystem::exists(a + "/config_effective.ini"));
  // trajectory.txt: one TUM line per processed frame.
  const std::string traj = readFile(a + "/trajectory.txt");
  EXPECT_EQ(std::count(traj.begin(), traj.end(), '\n'), 60);
}

TEST(SystemBadInput, MissingAndCorruptFramesAreSkippedAndCounted)
{
  if (!haveSharedData("visp_rbt")) GTEST_SKIP() << "../shared/data/visp_rbt is absent";
  namespace fs = std::filesystem;
  // A copy of 20 frames of visp_rbt with one missing and one corrupt image.
  const fs::path d = fs::path(outDir("bad_frames_input"));
  fs::create_directories(d / "rgb");
  fs::copy_file(sharedData("visp_rbt") + "/calib.txt", d / "calib.txt");
  std::ofstream rgb(d / "rgb.txt");
  std::ifstream src(sharedData("visp_rbt") + "/rgb.txt");
  std::string line;
  int n = 0;
  while (std::getline(src, line) && n < 20)
  {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream is(line);
    std::string t, p;
    is >> t >> p;
    rgb << line << "\n";
    if (n == 7) std::ofstream(d / p) << "not a png";                      // corrupt
    else if (n != 12) fs::copy_file(sharedData("visp_rbt") + "/" + p, d / p);  // 12: missing
    ++n;
  }
  rgb.close();
  app::TRunSummary s;
  ASSERT_EQ(runApp({sourceDir() + "/ini/single.ini", d.string(), "--out", outDir("bad_frames")}, &s), 0);
  EXPECT_EQ(s.framesRead, 20u);
  EXPECT_EQ(s.framesSkipped, 2u);
  EXPECT_EQ(s.framesProcessed, 18u);
  ASSERT_EQ(s.skipReasons.size(), 2u);
  EXPECT_NE(s.skipReasons[0].find("color_image_0007"), std::string::npos) << s.skipReasons[0];
  EXPECT_NE(s.skipReasons[1].find("color_image_0012"), std::string::npos) << s.skipReasons[1];
}

TEST(SystemRealData, MonoslamTestseqBlackoutIsRelocalisedOnTheSameMap)
{
  // Real images, a covered lens for 2 s (frames 400-459 black): the full system keeps its map, finds it
  // again in the first normal frame ([slam] relocalise) and goes on in the same frame and scale. The
  // trajectory after the blackout is compared with the undamaged run's (same start, SE(3) alignment,
  // no rescaling): measured 1.48 % of its extent (2026-11-27) (69 % when the map was rebuilt).
  if (!haveSharedData("monoslam_testseq")) GTEST_SKIP() << "../shared/data/monoslam_testseq is absent";
  const std::string data = sharedData("monoslam_testseq");
  const std::string folder = outDir("testseq_blackout_input");
  std::filesystem::create_directories(folder);
  std::filesystem::copy_file(data + "/calib.txt", folder + "/calib.txt",
                             std::filesystem::copy_options::overwrite_existing);
  {
    std::ofstream black(folder + "/black.pgm", std::ios::binary);
    black << "P5\n320 240\n255\n" << std::string(320 * 240, '\0');
  }
  std::ifstream in(data + "/rgb.txt");
  std::ofstream out(folder + "/rgb.txt");
  std::string line;
  int k = 0;
  double tAfter = 0;
  while (std::getline(in, line))
  {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ss(line);
    std::string ts, path;
    ss >> ts >> path;
    if (k == 460) tAfter = std::stod(ts);
    out << ts << ' ' << ((k >= 400 && k < 460) ? std::string("black.pgm") : data + "/" + path) << '\n';
    ++k;
  }
  out.close();
  ASSERT_EQ(k, 1000);
  const auto run = [&](const std::string& input, const std::string& name) {
    const auto dir = outDir(name);
    EXPECT_EQ(runApp({sourceDir() + "/ini/imm7-shadow.ini", input, "--out", dir}), 0);
    return dir;
  };
  const auto ref = run(data, "testseq_blackout_ref");
  const auto dmg = run(folder, "testseq_blackout");
  const auto rows = readCsv(dmg + "/frame_stats.csv");
  ASSERT_EQ(rows.size(), 1001u);
  const auto col = [&](const std::string& name) {
    const auto it = std::find(rows[0].begin(), rows[0].end(), name);
    return static_cast<std::size_t>(it - rows[0].begin());
  };
  EXPECT_EQ(std::stoi(rows[1 + 460][col("relocalised")]), 1);
  EXPECT_GE(std::stoi(rows[1 + 460][col("reloc_inliers")]), 8);
  EXPECT_EQ(std::stoi(rows[1 + 459][col("lost_frames")]), 59);
  const auto after = [&](const core::TTrajectory& t) {
    core::TTrajectory o;
    for (const auto& p : t)
      if (p.timestamp >= tAfter - 1e-6) o.push_back(p);
    return o;
  };
  const auto a = eval::computeAte(after(core::readTumTrajectory(dmg + "/trajectory.txt")),
                                  after(core::readTumTrajectory(ref + "/trajectory.txt")), eval::EAlignment::SE3);
  std::printf("testseq blackout 400-459, imm7-shadow: after the blackout vs the undamaged run (SE3) %.4f = %.2f %% of "
              "extent\n",
              a.rmse, 100 * a.rmseOverExtent);
  EXPECT_LT(a.rmseOverExtent, 0.0178);  // measured 1.48 % of extent (2026-11-27); limit ~1.2x
}

TEST(SystemSynthetic, RelativePosesCarryTheFilterCovarianceAndLeaveTheEstimateAsItWas)
{
  // [output] relative_pose_lag = 10 on the hand-held render without its boxes (seed 1), the default
  // configuration: every frame from the 10th on reports its motion over 10 frames, the estimate is the
  // run's without clones (to rounding), and the reported covariance holds the rendered truth: the
  // rotation's NEES inside the chi-square(3) 95 % bound on 95.2 % of the rows (measured), median 0.31
  // (a consistent filter's 2.37: on rendered images the filter's relative rotation is cautious).
  const std::string data = outDir("data-relative-poses-static-1");
  sim::CSimulator(sim::TScenario::loadFile(sourceDir() + "/ini/scenarios/handheld-moving.ini",
                                           {"scenario.seed=1", "objects.enabled=false"}))
      .writeDataset(data);
  app::TRunSummary with, without;
  const std::string out = outDir("relative-poses"), plain = outDir("relative-poses-off");
  ASSERT_EQ(runApp({sourceDir() + "/ini/imm7-shadow.ini", data, "--out", out, "--set", "output.relative_pose_lag=10"},
                   &with),
            0);
  ASSERT_EQ(runApp({sourceDir() + "/ini/imm7-shadow.ini", data, "--out", plain}, &without), 0);
  ASSERT_TRUE(with.ate.has_value() && without.ate.has_value());
  EXPECT_NEAR(with.ate->rmseOverPath, without.ate->rmseOverPath, 0.01 * without.ate->rmseOverPath);
  EXPECT_FALSE(std::filesystem::exists(plain + "/relative_poses.csv"));
  const auto rows = eval::readRelativePosesCsv(out + "/relative_poses.csv");
  EXPECT_EQ(rows.size(), with.framesProcessed - 10);
  const auto r = eval::computeRelativeNees(rows, core::readTumTrajectory(data + "/groundtruth.txt"), 0);
  ASSERT_EQ(r.nUsed, rows.size());
  const double inside = static_cast<double>(std::count_if(r.rotation.begin(), r.rotation.end(),
                                                          [](double x) { return x <= 7.815; })) /
                        static_cast<double>(r.rotation.size());
  std::printf("relative rotation NEES: median %.3f, inside the 95 %% bound on %.1f %% of %zu rows\n",
              eval::median(r.rotation), 100 * inside, r.rotation.size());
  EXPECT_GE(inside, 0.9);
  EXPECT_LT(eval::median(r.rotation), 2.366);
}
