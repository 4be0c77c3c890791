/* The IMM paper's claims reproduced on the rendered paper-shaped scenario (stationary -> rotation ->
 * general -> rotation -> stationary) and on the EuRoC camera at rest: segmentation, consistent
 * start-up (no false depth), smaller search regions, the Occam property, accuracy vs the single model. */
#include "test_helpers.h"

#include <immslam/eval/segmentation.h>
#include <immslam/eval/statistics.h>
#include <immslam/sim/CSyntheticSource.h>

#include <algorithm>
#include <cmath>

using namespace immslam;
using namespace immslam::test;

namespace
{
struct TRun
{
  std::vector<std::vector<std::string>> probs, stats;
  eval::TModelProbabilities mp;  ///< model_probabilities.csv as read by slam-eval
  app::TRunSummary summary;
};

TRun runOn(const std::string& config, const std::vector<std::string>& extra, const std::string& name)
{
  TRun r;
  const auto out = outDir(name);
  std::vector<std::string> args{sourceDir() + "/ini/" + config, "--out", out};
  args.insert(args.end(), extra.begin(), extra.end());
  EXPECT_EQ(runApp(args, &r.summary), 0);
  r.probs = readCsv(out + "/model_probabilities.csv");
  r.mp = eval::readModelProbabilitiesCsv(out + "/model_probabilities.csv");
  r.stats = readCsv(out + "/frame_stats.csv");
  return r;
}

double col(const std::vector<std::string>& row, const std::vector<std::string>& head, const std::string& name)
{
  for (std::size_t j = 0; j < head.size(); ++j)
    if (head[j] == name) return std::stod(row[j]);
  ADD_FAILURE() << "no column " << name;
  return NAN;
}
}  // namespace

TEST(IMMPaper, RenderedPaperScenarioReproducesTheClaims)
{
  const std::vector<std::string> scen{"--set", "input.scenario=scenarios/paper.ini"};
  const TRun imm = runOn("imm7.ini", scen, "paper_imm7");
  const TRun single = runOn("single.ini", scen, "paper_single");
  ASSERT_TRUE(imm.summary.ate && single.summary.ate);

  // True labels of the same rendered sequence.
  sim::CSyntheticSource src(sourceDir() + "/ini/scenarios/paper.ini");
  const std::size_t n = imm.mp.times.size();
  std::vector<std::string> labels;
  for (std::size_t k = 0; k < n; ++k) labels.push_back(sim::toString(src.label(k)));

  // Segmentation: the family with the highest summed probability matches the true label (frames
  // within 0.5 s of a label change not counted).
  const eval::TSegmentationResult seg =
      eval::segmentationAccuracy(imm.mp.times, imm.mp.modelNames, imm.mp.probs, labels, 0.5);
  const std::vector<double>& transitions = seg.transitions;
  ASSERT_EQ(transitions.size(), 4u);
  const double segmentation = seg.accuracy;

  // Consistent start-up (Fig. 3): share of features with a known depth at the end of the
  // stationary + rotation start.
  auto knownShare = [&](const TRun& r) {
    const double tEnd = transitions[1];
    std::size_t best = 1;
    for (std::size_t k = 1; k < r.stats.size(); ++k)
      if (std::abs(std::stod(r.stats[k][0]) - tEnd) < std::abs(std::stod(r.stats[best][0]) - tEnd)) best = k;
    return col(r.stats[best], r.stats[0], "n_depth_known") / col(r.stats[best], r.stats[0], "n_map");
  };
  // Search regions (Fig. 5): median of the mean search-ellipse area.
  auto medianArea = [](const TRun& r) {
    std::vector<double> a;
    for (std::size_t k = 2; k < r.stats.size(); ++k) a.push_back(col(r.stats[k], r.stats[0], "mean_search_area_px2"));
    return eval::median(a);
  };
  auto medianMs = [](const TRun& r) {
    std::vector<double> a;
    for (std::size_t k = 2; k < r.stats.size(); ++k) a.push_back(col(r.stats[k], r.stats[0], "time_ms"));
    return eval::median(a);
  };
  // Occam (Fig. 4): the most general model's probability.
  int lowGeneral = 0;
  for (std::size_t k = 1; k <= n; ++k) lowGeneral += std::stod(imm.probs[k].back()) < 0.05 ? 1 : 0;

  const double areaRatio = medianArea(imm) / medianArea(single);
  std::printf("paper scenario: segmentation %.3f; known depth at t=%.2f: IMM %.3f, single %.3f; median search "
              "area IMM %.2f px2 vs single %.2f px2 (ratio %.3f); %s < 0.05 on %.3f of frames; ATE/path IMM %.3f %% "
              "vs single %.3f %%; median frame time IMM %.2f ms vs single %.2f ms (ratio %.2f, not asserted)\n",
              segmentation, transitions[1], knownShare(imm), knownShare(single), medianArea(imm), medianArea(single),
              areaRatio, imm.probs[0].back().c_str(), static_cast<double>(lowGeneral) / n,
              100 * imm.summary.ate->rmseOverPath, 100 * single.summary.ate->rmseOverPath, medianMs(imm),
              medianMs(single), medianMs(imm) / medianMs(single));
  // Limits at ~1.2x the figures measured on this scenario (seed 7) on 2026-11-27 (errors at most 1.2x,
  // shares at most 1.2x further from their ideal): segmentation 0.996; known depth IMM 0.000, single
  // 1.000; search-area ratio 0.079; most general model < 0.05 on 0.997 of frames; ATE IMM 0.542 %,
  // single 1.351 % of path. Other seeds (imm-render --seed S, imm-monoslam): area ratio 0.078 / 0.070,
  // ATE IMM 1.15 / 0.52 %, single 1.87 / 1.49 % (seeds 11 / 23).
  EXPECT_GE(segmentation, 0.995);
  EXPECT_LE(knownShare(imm), 0.01);    // the IMM does not claim depth from the rotation start ...
  EXPECT_GE(knownShare(single), 0.8);  // ... the single model does (the contrast of Fig. 3)
  EXPECT_LE(areaRatio, 0.095);
  EXPECT_GT(static_cast<double>(lowGeneral) / n, 0.996);
  EXPECT_LE(imm.summary.ate->rmseOverPath, 0.0065);
  EXPECT_LE(single.summary.ate->rmseOverPath, 0.0162);
  EXPECT_LE(imm.summary.ate->rmse, single.summary.ate->rmse);
}

TEST(IMMPaper, EurocCameraAtRestIsStationary)
{
  if (!haveSharedData("euroc_v101_stationary")) GTEST_SKIP() << "../shared/data/euroc_v101_stationary is absent";
  const TRun imm = runOn("imm7.ini", {sharedData("euroc_v101_stationary")}, "euroc_imm7");
  const eval::TFamilyProbabilities fam = eval::familyProbabilities(imm.mp.modelNames, imm.mp.probs);
  const auto stationary = std::find(fam.families.begin(), fam.families.end(), "stationary") - fam.families.begin();
  ASSERT_LT(stationary, static_cast<std::ptrdiff_t>(fam.families.size()));
  int ok = 0, counted = 0;
  double minP = 1;
  for (Eigen::Index k = 9; k < fam.probs.rows(); ++k)  // from the 10th frame on
  {
    const double p = fam.probs(k, stationary);
    ok += p >= 0.9 ? 1 : 0;
    minP = std::min(minP, p);
    ++counted;
  }
  const double share = static_cast<double>(ok) / counted;
  std::printf("euroc at rest: stationary family >= 0.9 on %d of %d frames (%.3f) from the 10th; min %.3f\n", ok,
              counted, share, minP);
  // The target: every frame from the 10th. The Vicon ground truth shows the camera turning by
  // up to 2.7 mrad (1.2 px) during the sequence; the bank's shake (imm.shake_px, in every model) lets
  // the stationary model explain it, while a rotation model, which has the same shake, has nothing to
  // add (doc/imm.md).
  EXPECT_EQ(ok, counted);
  // Measured min 0.962 (2026-11-27): the stationary family's shortfall from 1 (0.038) at most 1.2x.
  EXPECT_GE(minP, 0.954);
}
