/* Tests: the shadow filter on images (CShadowTracker) — a short rendered sequence (a textured
 * background plane and a textured square moving in front of it, seen by a hand-held camera): features
 * are tracked by the tracker's active search and those on the moving square are classified dynamic. (The per-frame
 * cost on the same scene is a benchmark: tests/benchmarks/bench_shadow.) */
#include <gtest/gtest.h>
#include <immslam/frontend/frontend.h>
#include <immslam/tracking/CShadowTracker.h>

#include <algorithm>
#include <map>

#include "shadow_image_scene.h"

using namespace immslam;
using namespace immslam::shadow;
using namespace immslam::shadow::test;

namespace
{
/** Truth of a feature from its first pixel: 1 on the square's interior, 0 on the background away
 * from the square, -1 near the square's border (corners there mix both: not scored). */
int truthAt(const cv::Mat& onSquare, const Vec2& uv)
{
  const int u = int(std::lround(uv.x())), v = int(std::lround(uv.y()));
  int lo = 255, hi = 0;
  for (int dv = -7; dv <= 7; ++dv)
    for (int du = -7; du <= 7; ++du)
    {
      const int x = std::clamp(u + du, 0, onSquare.cols - 1), y = std::clamp(v + dv, 0, onSquare.rows - 1);
      lo = std::min<int>(lo, onSquare.at<uchar>(y, x));
      hi = std::max<int>(hi, onSquare.at<uchar>(y, x));
    }
  if (lo == 255) return 1;
  if (hi == 0) return 0;
  return -1;
}
}  // namespace

TEST(ShadowImage, TracksAndClassifiesAMovingSquare)
{
  const TScene scene;
  CShadowFilter::TOptions opts;
  CShadowTracker filter(opts, scene.cam);
  frontend::TDetectorParams det;
  det.gridCols = 10;
  det.gridRows = 8;
  std::map<std::int64_t, int> truth;
  std::map<std::int64_t, EShadowClass> decided;
  int searched = 0, measured = 0, timedOut = 0, lost = 0;
  const int nFrames = 240;
  for (int k = 0; k < nFrames; ++k)
  {
    cv::Mat onSquare;
    const cv::Mat grey = scene.render(k, &onSquare);
    const TShadowReport& rep = filter.processFrame(scene.motion(k), grey);
    searched += rep.nSearched;
    measured += rep.nMeasured;
    timedOut += rep.nTimedOut;
    lost += rep.nLost;
    for (const auto& d : rep.decisions) decided[d.id] = d.cls;
    // Keep ~30 features: new corners in cells free of shadow features.
    const int want = 30 - static_cast<int>(filter.size());
    if (want > 0 && k < nFrames - 90)
    {
      std::vector<Vec2> uv;
      for (const auto& c : frontend::detectInEmptyCells(grey, filter.occupiedPixels(), want, det)) uv.push_back(c.uv);
      const auto ids = filter.addFeatures(grey, uv);
      for (size_t i = 0; i < ids.size(); ++i)
        if (ids[i] >= 0) truth[ids[i]] = truthAt(onSquare, uv[i]);
    }
  }
  int sqTotal = 0, sqDynamic = 0, sqStatic = 0, bgTotal = 0, bgStatic = 0, bgDynamic = 0;
  for (const auto& [id, t] : truth)
  {
    const auto it = decided.find(id);
    const EShadowClass c = it == decided.end() ? EShadowClass::Pending : it->second;
    if (t == 1)
    {
      ++sqTotal;
      sqDynamic += c == EShadowClass::Dynamic;
      sqStatic += c == EShadowClass::Static;
    }
    else if (t == 0)
    {
      ++bgTotal;
      bgStatic += c == EShadowClass::Static;
      bgDynamic += c == EShadowClass::Dynamic;
    }
  }
  std::printf("[ shadow   ] image sequence: %d frames, search success %.1f %% (%d searches)\n", nFrames,
              100.0 * measured / std::max(1, searched), searched);
  std::printf("[ shadow   ] pending features timed out %d, lost %d\n", timedOut, lost);
  std::printf("[ shadow   ] features on the moving square: %d, dynamic %d, static %d\n", sqTotal, sqDynamic, sqStatic);
  std::printf("[ shadow   ] features on the background:    %d, static %d, dynamic %d\n", bgTotal, bgStatic, bgDynamic);
  // Every printed figure asserted, limits at ~1.2x the measured ones (deterministic run, measured
  // 2026-11-27: search success 92.3 % of 5353, 4 timed out, 35 lost; square 15, all dynamic;
  // background 35: 10 static, 1 dynamic).
  EXPECT_GE(sqTotal, 12);
  EXPECT_EQ(sqStatic, 0);
  EXPECT_GE(sqDynamic, 0.8 * sqTotal);
  EXPECT_GE(bgTotal, 29);
  EXPECT_LE(bgDynamic, 0.06 * bgTotal);
  EXPECT_GE(bgStatic, 0.23 * bgTotal);
  EXPECT_GE(double(measured) / searched, 0.907);  // failed searches 7.7 % -> at most 9.3 %
  EXPECT_LE(timedOut, 5);
  EXPECT_LE(lost, 42);
}

TEST(ShadowImage, ImageStepIsTheFilterStepWithTheSearchedMatches)
{
  // The image path ends in the filter's update with given matches: the tracker's frame equals
  // predict / update(its associations) / finishFrame on a second filter, bit for bit.
  const TScene scene;
  CShadowFilter::TOptions opts;
  CShadowTracker tracker(opts, scene.cam);
  CShadowFilter twin(opts, scene.cam);
  frontend::TDetectorParams det;
  int compared = 0;
  for (int k = 0; k < 30; ++k)
  {
    const cv::Mat grey = scene.render(k);
    const TShadowReport& rep = tracker.processFrame(scene.motion(k), grey);
    std::vector<TShadowMatch> matches;
    for (const auto& v : rep.views)
      if (v.searched) matches.push_back({v.id, v.measured, v.uv});
    twin.predict(scene.motion(k));
    twin.update(matches);
    const TShadowReport& trep = twin.finishFrame();
    ASSERT_EQ(trep.views.size(), rep.views.size());
    for (std::size_t i = 0; i < rep.views.size(); ++i)
    {
      EXPECT_EQ(trep.views[i].id, rep.views[i].id);
      EXPECT_EQ(trep.views[i].uv, rep.views[i].uv);
      EXPECT_EQ(trep.views[i].S, rep.views[i].S);
      ++compared;
    }
    if (tracker.size() < 20)
    {
      std::vector<Vec2> uv;
      for (const auto& c : frontend::detectInEmptyCells(grey, tracker.occupiedPixels(), 20, det)) uv.push_back(c.uv);
      const auto ids = tracker.addFeatures(grey, uv);
      std::vector<Vec2> kept;
      for (std::size_t i = 0; i < ids.size(); ++i)
        if (ids[i] >= 0) kept.push_back(uv[i]);
      twin.addFeatures(kept);
    }
  }
  EXPECT_GT(compared, 100);
}

TEST(ShadowImage, BadImagesAndFeaturesWithoutPatches)
{
  const TScene scene;
  CShadowTracker tracker(CShadowFilter::TOptions(), scene.cam);
  EXPECT_THROW(tracker.processFrame(scene.motion(0), cv::Mat()), std::runtime_error);
  EXPECT_THROW(tracker.addFeatures(cv::Mat(3, 3, CV_8UC1), {Vec2(10, 10)}), std::runtime_error);
  // Added without an image: held by the filter, never searched in an image.
  const auto ids = tracker.addFeatures(cv::Mat(), {Vec2(100, 80), Vec2(150, 90)});
  ASSERT_EQ(ids.size(), 2u);
  EXPECT_GE(ids[0], 0);
  EXPECT_EQ(tracker.patchOf(ids[0]), nullptr);
  const TShadowReport& rep = tracker.processFrame(scene.motion(1), scene.render(1));
  EXPECT_EQ(rep.nSearched, 0);
  EXPECT_EQ(tracker.size(), 2u);
}
