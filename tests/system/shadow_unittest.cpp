/* MonoSLAMBOT (paper 2) at system level: static/dynamic classification against ground truth, and the
 * map kept clean of moving objects (Fig. 5 as numbers). */
#include "test_helpers.h"

#include <immslam/sim/CSyntheticSource.h>

#include <cmath>
#include <map>

using namespace immslam;
using namespace immslam::test;

namespace
{
struct TConfusion
{
  int movingStatic = 0, movingDynamic = 0, staticStatic = 0, staticDynamic = 0, unmatched = 0;
  double movingAsStatic() const { return movingStatic / std::max(1.0, double(movingStatic + movingDynamic)); }
  double staticAsDynamic() const { return staticDynamic / std::max(1.0, double(staticStatic + staticDynamic)); }
  void add(bool moving, const std::string& cls)
  {
    (moving ? (cls == "static" ? movingStatic : movingDynamic) : (cls == "static" ? staticStatic : staticDynamic))++;
  }
};
}  // namespace

TEST(ShadowSystem, MonoslammotSynth19ClassificationAgainstPointGroundTruth)
{
  if (!haveSharedData("monoslammot_synth19")) GTEST_SKIP() << "../shared/data/monoslammot_synth19 is absent";
  const auto out = outDir("synth19_full");
  app::TRunSummary s;
  ASSERT_EQ(runApp({sourceDir() + "/ini/imm7-shadow.ini", sharedData("monoslammot_synth19"), "--out", out, "--set",
                    "output.plots=false"},
                   &s),
            0);
  // Ground truth: per timestamp the projections of the static and moving points.
  std::map<long long, std::vector<std::tuple<double, double, bool>>> gt;
  std::ifstream f(sharedData("monoslammot_synth19") + "/points_groundtruth.txt");
  std::string line;
  while (std::getline(f, line))
  {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream is(line);
    double t, x, y, z, u, v;
    long id;
    std::string kind;
    is >> t >> id >> kind >> x >> y >> z >> u >> v;
    gt[std::llround(t * 1e4)].emplace_back(u, v, kind == "moving");
  }
  TConfusion c;
  const auto rows = readCsv(out + "/classifications.csv");
  for (std::size_t i = 1; i < rows.size(); ++i)
  {
    const double u = std::stod(rows[i][3]), v = std::stod(rows[i][4]);
    double best = 1e9;
    bool moving = false;
    for (const auto& [gu, gv, m] : gt[std::llround(std::stod(rows[i][0]) * 1e4)])
      if (const double d = std::hypot(gu - u, gv - v); d < best) best = d, moving = m;
    if (best > 3)
      ++c.unmatched;  // a corner that is not one of the ground-truth points
    else
      c.add(moving, rows[i][2]);
  }
  std::printf("synth19: moving->static %d/%d (%.3f), static->dynamic %d/%d (%.3f), %d decisions on other corners; "
              "ATE %.3f %% of path\n",
              c.movingStatic, c.movingStatic + c.movingDynamic, c.movingAsStatic(), c.staticDynamic,
              c.staticStatic + c.staticDynamic, c.staticAsDynamic(), c.unmatched, 100 * s.ate->rmseOverPath);
  EXPECT_GE(c.movingStatic + c.movingDynamic, 10);
  EXPECT_LE(c.movingAsStatic(), 0.01);
  EXPECT_LE(c.staticAsDynamic(), 0.05);
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
  TConfusion c;
  const auto rows = readCsv(outMoving + "/classifications.csv");
  for (std::size_t i = 1; i < rows.size(); ++i)
  {
    const double t = std::stod(rows[i][0]);
    const std::size_t k = static_cast<std::size_t>(std::llround(t * 30.0));
    const cv::Mat mask = src.mask(k);
    const int u = static_cast<int>(std::lround(std::stod(rows[i][3]))), v = static_cast<int>(std::lround(std::stod(rows[i][4])));
    bool moving = false;
    for (int dv = -1; dv <= 1; ++dv)
      for (int du = -1; du <= 1; ++du)
        if (u + du >= 0 && v + dv >= 0 && u + du < mask.cols && v + dv < mask.rows)
          moving |= mask.at<std::uint8_t>(v + dv, u + du) > 0;
    c.add(moving, rows[i][2]);
  }
  std::printf("handheld-moving: moving->static %d/%d, static->dynamic %d/%d; ATE/path: full system %.3f %% with moving "
              "objects vs %.3f %% without (ratio %.2f); IMM without shadow filter %.3f %%; single model %.3f %% with "
              "moving objects vs %.3f %% without\n",
              c.movingStatic, c.movingStatic + c.movingDynamic, c.staticDynamic, c.staticStatic + c.staticDynamic,
              100 * withShadow.ate->rmseOverPath, 100 * still.ate->rmseOverPath,
              withShadow.ate->rmse / still.ate->rmse, 100 * noShadow.ate->rmseOverPath,
              100 * singleMoving.ate->rmseOverPath, 100 * singleStill.ate->rmseOverPath);
  EXPECT_EQ(c.movingStatic, 0);
  EXPECT_LE(c.staticAsDynamic(), 0.05);
  EXPECT_LE(withShadow.ate->rmseOverPath, 0.01);
}
