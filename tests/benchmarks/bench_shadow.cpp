/* imm-monoslam — benchmark of the shadow filter on images: CShadowFilter::processFrame (predict,
 * active search, update, classify) on the rendered scene of shadow_image_unittest (320x240, a
 * textured plane and a moving textured square, hand-held camera) with 20 and 50 shadow features
 * held (new corners added in empty cells every frame; nothing times out). Time = ms per frame; the
 * per-stage times of the filter's own report are counters (ms per frame). Formerly the ctest entry
 * ShadowImage.PerFrameCost, which printed and asserted nothing. */
#include "bench_common.h"

#include <immslam/frontend/frontend.h>
#include <immslam/tracking/CShadowTracker.h>

#include <algorithm>
#include <chrono>
#include <vector>

#include "shadow_image_scene.h"

namespace
{
using namespace immslam;
using namespace immslam::shadow;

/** The 60 rendered frames of the scene (rendered once). */
const std::vector<cv::Mat>& sceneFrames(const test::TScene& scene)
{
  static const std::vector<cv::Mat> frames = [&] {
    std::vector<cv::Mat> f;
    for (int k = 0; k < 60; ++k) f.push_back(scene.render(k));
    return f;
  }();
  return frames;
}

/** One iteration: a fresh filter over the 60 frames, kept at `n` features; the reported time is
 * processFrame's per frame over frames 10-59 (manual timing: rendering, detection and the untimed
 * start are excluded). */
void BM_ShadowProcessFrame(benchmark::State& st)
{
  static const test::TScene scene;
  const auto& frames = sceneFrames(scene);
  const int n = static_cast<int>(st.range(0));
  frontend::TDetectorParams det;
  det.gridCols = 10;
  det.gridRows = 8;
  det.minDistancePx = 8;
  double held = 0, tPred = 0, tSearch = 0, tUpd = 0, tCls = 0;
  long counted = 0;
  for (auto _ : st)
  {
    CShadowFilter::TOptions opts;
    opts.max_pending_frames = 1000;  // keep the features: the cost is measured with n held
    opts.static_min_velocity_px = 1e-6;
    CShadowTracker filter(opts, scene.cam);
    double seconds = 0;
    int timed = 0;
    for (int k = 0; k < static_cast<int>(frames.size()); ++k)
    {
      const auto t0 = std::chrono::steady_clock::now();
      const TShadowReport& rep = filter.processFrame(scene.motion(k), frames[k]);
      if (k >= 10)
      {
        seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        ++timed;
        held += rep.nPending + rep.nDynamic;
        tPred += rep.tPredictMs;
        tSearch += rep.tSearchMs;
        tUpd += rep.tUpdateMs;
        tCls += rep.tClassifyMs;
        ++counted;
      }
      const int want = n - static_cast<int>(filter.size());
      if (want > 0)
      {
        std::vector<Vec2> uv;
        for (const auto& c : frontend::detectInEmptyCells(frames[k], filter.occupiedPixels(), want, det))
          uv.push_back(c.uv);
        filter.addFeatures(frames[k], uv);
      }
    }
    st.SetIterationTime(seconds / std::max(1, timed));
  }
  const double c = static_cast<double>(std::max(1L, counted));
  st.counters["features_held"] = held / c;
  st.counters["predict_ms"] = tPred / c;
  st.counters["search_ms"] = tSearch / c;
  st.counters["update_ms"] = tUpd / c;
  st.counters["classify_ms"] = tCls / c;
}
BENCHMARK(BM_ShadowProcessFrame)->ArgName("features")->Arg(20)->Arg(50)->UseManualTime()->Unit(benchmark::kMillisecond);
}  // namespace

IMMSLAM_BENCHMARK_MAIN();
