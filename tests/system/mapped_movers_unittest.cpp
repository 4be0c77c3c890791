/* End-to-end: moving objects the map holds (issue 27; doc/shadow.md, "Movers in the map").
 *  - MappedMovers.ParkedBoxLeavesTheMapAsDynamicTracksWithItsPast: ini/scenarios/parked-mover.ini
 *    (a box mapped while it stands still for 3 s, then sliding at 2-3 px per frame, hand-held
 *    camera): its SLAM features are searched beyond their ellipse, rejected, handed over with their
 *    id and decided dynamic, and their tracks in tracks.csv start where the map held them.
 *  - FirstMapMovers.StillCameraFirstMapIsTestedFromTheFirstFrame: ini/scenarios/still-movers.ini
 *    (three boxes moving in view from the first frame, camera at rest, default config): the first
 *    map's features go on probation in the shadow filter; the depth-free test decides them.
 * Truth: the renderer's masks (an object only while it moves). */
#include <gtest/gtest.h>
#include <immslam/core/TTrajectory.h>
#include <immslam/eval/ate.h>
#include <immslam/sim/CSyntheticSource.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <set>

#include "test_helpers.h"

namespace immslam::test
{
namespace
{
/** A decision of classifications.csv. */
struct TDecisionRow
{
  double t = 0;
  std::int64_t id = -1;
  bool dynamic = false;
  Vec2 uv = Vec2::Zero();
};

std::vector<TDecisionRow> readDecisions(const std::string& path)
{
  std::vector<TDecisionRow> out;
  const auto rows = readCsv(path);
  for (std::size_t i = 1; i < rows.size(); ++i)
    if (rows[i].size() >= 5)
      out.push_back({std::stod(rows[i][0]), std::stoll(rows[i][1]), rows[i][2] == "dynamic",
                     Vec2(std::stod(rows[i][3]), std::stod(rows[i][4]))});
  return out;
}

/** A moving object's mask within 1 px of uv at the frame of time t (30 Hz). */
bool onMover(const sim::CSyntheticSource& src, double t, const Vec2& uv)
{
  const cv::Mat m = src.mask(static_cast<std::size_t>(std::llround(t * 30.0)));
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx)
    {
      const int x = static_cast<int>(std::lround(uv.x())) + dx, y = static_cast<int>(std::lround(uv.y())) + dy;
      if (x >= 0 && y >= 0 && x < m.cols && y < m.rows && m.at<std::uint8_t>(y, x)) return true;
    }
  return false;
}
}  // namespace

TEST(MappedMovers, ParkedBoxLeavesTheMapAsDynamicTracksWithItsPast)
{
  // Measured (seed 7, 150 frames): 7 SLAM features on the box when it starts (frame 90); at frame
  // 93 four are handed over (three rejections in a row: found beyond their ellipse), three lost;
  // first dynamic decision on the box at frame 106 (16 frames after the start), 2 dynamic decisions
  // on it (a translating camera's lone dynamic verdict waits for another feature nearby that moves:
  // doc/shadow.md, "Decision rules"), none static, both with their mapped past (tracks.csv rows at 0
  // and 3 s). Limits at about 1.2 x.
  const auto out = outDir("parked_mover");
  ASSERT_EQ(runApp({sourceDir() + "/ini/imm7-shadow.ini", "--out", out, "--frames", "150", "--set",
                    "input.scenario=scenarios/parked-mover.ini"}),
            0);
  const double start = 3.0;
  sim::CSyntheticSource src(sourceDir() + "/ini/scenarios/parked-mover.ini", {}, 150);
  double first = -1;
  int dynamicOnBox = 0, staticOnBox = 0;
  std::set<std::int64_t> boxTracks;
  for (const auto& d : readDecisions(out + "/classifications.csv"))
  {
    if (d.t < start - 1e-9 || !onMover(src, d.t, d.uv)) continue;
    if (!d.dynamic)
    {
      ++staticOnBox;
      continue;
    }
    ++dynamicOnBox;
    boxTracks.insert(d.id);
    if (first < 0) first = d.t;
  }
  // Tracks that start where the map held them: rows before the box moved.
  std::set<std::int64_t> withPast;
  const auto tracks = readCsv(out + "/tracks.csv");
  for (std::size_t i = 1; i < tracks.size(); ++i)
    if (tracks[i].size() >= 2 && std::stod(tracks[i][0]) < start + 1e-9 && boxTracks.count(std::stoll(tracks[i][1])))
      withPast.insert(std::stoll(tracks[i][1]));
  const double latency = first < 0 ? 1e9 : (first - start) * 30.0;
  std::printf("parked box: first dynamic decision %.0f frames after it starts; %d dynamic, %d static on it; %zu "
              "tracks with their mapped past\n",
              latency, dynamicOnBox, staticOnBox, withPast.size());
  EXPECT_LE(latency, 20.0);
  EXPECT_GE(dynamicOnBox, 2);
  EXPECT_EQ(staticOnBox, 0);
  EXPECT_GE(withPast.size(), 2u) << "the tracks of the box's mapped features must start where it was mapped";
}

TEST(FirstMapMovers, StillCameraFirstMapIsTestedFromTheFirstFrame)
{
  // Measured (seed 7, 120 frames, default config): the first map's copies are decided from frame 7
  // on: the first dynamic decision on a box at frame 7 (main before: 18, from a feature handed over
  // after its rejections), 14 first-map features confirmed static by frame 32 (static decisions wait
  // for a track of 30 frames while the camera does not translate; before, 21 at frame 10),
  // none of the first map's features on a box static; rotation RMSE 0.011 deg. Limits at about 1.2 x. (A watched feature
  // born at frame 54 on a part of a box that stays put in the image is decided static at frame 63:
  // the watched features' rates are MoversWithoutTranslation's.)
  const auto out = outDir("first_map_still");
  ASSERT_EQ(runApp({sourceDir() + "/ini/imm7-shadow.ini", "--out", out, "--frames", "120", "--set",
                    "input.scenario=scenarios/still-movers.ini", "--set", "output.search_log=true"}),
            0);
  sim::CSyntheticSource src(sourceDir() + "/ini/scenarios/still-movers.ini", {}, 120);
  // The first map: the features SLAM searched for in the second frame.
  std::set<std::int64_t> firstMap;
  const auto searches = readCsv(out + "/searches.csv");
  for (std::size_t i = 1; i < searches.size(); ++i)
    if (searches[i].size() >= 2 && std::stod(searches[i][0]) * 30.0 < 1.5) firstMap.insert(std::stoll(searches[i][1]));
  ASSERT_GE(firstMap.size(), 20u);
  double firstDynamic = -1;
  int staticBy32 = 0, staticOnMovers = 0;
  for (const auto& d : readDecisions(out + "/classifications.csv"))
  {
    const bool moving = onMover(src, d.t, d.uv);
    if (d.dynamic && moving && firstDynamic < 0) firstDynamic = d.t;
    if (!d.dynamic && d.t * 30.0 <= 32.5) ++staticBy32;
    if (!d.dynamic && moving && firstMap.count(d.id)) ++staticOnMovers;
  }
  const auto est = core::readTumTrajectory(out + "/trajectory.txt");
  const auto gt = src.groundTruth();
  ASSERT_TRUE(gt.has_value());
  const double rot = eval::computeAte(est, *gt, eval::EAlignment::None).rotationRmseDeg;
  std::printf("still camera, movers in the first map (%zu features): first dynamic decision on a mover at frame %.0f; "
              "%d static decisions by frame 32; %d of the first map static on movers; rotation RMSE %.4f deg\n",
              firstMap.size(), firstDynamic * 30.0, staticBy32, staticOnMovers, rot);
  EXPECT_GE(firstDynamic, 0.0);
  EXPECT_LE(firstDynamic * 30.0, 9.0);
  EXPECT_GE(staticBy32, 11);
  EXPECT_EQ(staticOnMovers, 0);
  EXPECT_LT(rot, 0.014);
}
}  // namespace immslam::test
