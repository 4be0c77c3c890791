/* imm-monoslam — benchmarks of the image front end at 320x240 and 640x480: corner detection in the
 * empty cells of the grid (frontend::detectInEmptyCells), patch prediction (warping) and the active
 * search inside innovation ellipses of several areas (frontend::searchInEllipse).
 *
 * Frames: monoslam_testseq (320x240) and visp_rbt (640x480) from ../shared/data when present;
 * otherwise a frame of the built-in rendered scene at that size (the label says which). */
#include "bench_common.h"

#include <immslam/frontend/frontend.h>
#include <immslam/sim/CSimulator.h>
#include <immslam/sim/TScenario.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace
{
namespace frontend = immslam::frontend;
using immslam::Mat2;
using immslam::Vec2;
constexpr double kPi = 3.14159265358979323846;

/** Two consecutive grey frames (k and k+1) of one image size. */
struct TFramePair
{
  cv::Mat a, b;
  std::string origin;
};

/** The k-th image listed in folder/rgb.txt, grey, or empty. */
cv::Mat readDatasetFrame(const std::string& folder, int k)
{
  std::ifstream f(std::filesystem::path(folder) / "rgb.txt");
  std::string line;
  int i = 0;
  while (std::getline(f, line))
  {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream is(line);
    double t;
    std::string name;
    if (!(is >> t >> name)) continue;
    if (i++ == k) return cv::imread((std::filesystem::path(folder) / name).string(), cv::IMREAD_GRAYSCALE);
  }
  return {};
}

/** Frames of the given width (320 or 640): real when the shared data exist, else rendered. */
const TFramePair& frames(int width)
{
  static std::map<int, TFramePair> cache;
  if (auto it = cache.find(width); it != cache.end()) return it->second;
  TFramePair p;
  const std::string folder = immslam::bench::sharedDataDir() + (width == 320 ? "/monoslam_testseq" : "/visp_rbt");
  const int k = width == 320 ? 300 : 50;
  if (immslam::bench::datasetPresent(folder))
  {
    p.a = readDatasetFrame(folder, k);
    p.b = readDatasetFrame(folder, k + 1);
    p.origin = std::filesystem::path(folder).filename().string() + " frames " + std::to_string(k) + "," +
               std::to_string(k + 1);
  }
  if (p.a.empty() || p.b.empty() || p.a.cols != width)
  {
    const std::string cam = width == 320 ? "pinhole 320 240 240 240 159.5 119.5" : "pinhole 640 480 480 480 319.5 239.5";
    const immslam::sim::CSimulator sim(immslam::sim::TScenario::builtinDefault({"scenario.camera=" + cam}));
    p.a = sim.render(60).grey;
    p.b = sim.render(61).grey;
    p.origin = "rendered (built-in scene) frames 60,61";
  }
  return cache.emplace(width, p).first->second;
}

/** Predicted positions of the features already tracked: a jittered grid of nOccupied points. */
std::vector<Vec2> occupiedPoints(const cv::Mat& img, int nOccupied)
{
  std::vector<Vec2> occ;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(0, 1);
  for (int i = 0; i < nOccupied; ++i) occ.emplace_back(img.cols * U(rng), img.rows * U(rng));
  return occ;
}

// Detection of new corners: 30 at start-up (nothing occupied), or 10 with 30 features tracked.
void BM_DetectInEmptyCells(benchmark::State& st)
{
  const int width = static_cast<int>(st.range(0));
  const int nOcc = static_cast<int>(st.range(1));
  const auto& f = frames(width);
  const auto occ = occupiedPoints(f.a, nOcc);
  const int maxNew = nOcc == 0 ? 30 : 10;
  frontend::TDetectorParams p;  // the [slam] defaults: FAST 20, 8x6 grid, 12 px, Shi-Tomasi 0.01
  p.borderPx = 11;
  std::size_t found = 0;
  for (auto _ : st)
  {
    const auto c = frontend::detectInEmptyCells(f.a, occ, maxNew, p);
    found = c.size();
    benchmark::DoNotOptimize(c.data());
  }
  st.SetLabel(f.origin);
  st.counters["corners"] = static_cast<double>(found);
}
BENCHMARK(BM_DetectInEmptyCells)
    ->ArgNames({"width", "occupied"})
    ->ArgsProduct({{320, 640}, {0, 30}})
    ->Unit(benchmark::kMicrosecond);

/** Up to 30 features of frame a (patches), with their pixel in frame a (the search centre in b). */
struct TFeatures
{
  std::vector<frontend::CFeaturePatch> patches;
  std::vector<Vec2> uv;
};
const TFeatures& features(int width)
{
  static std::map<int, TFeatures> cache;
  if (auto it = cache.find(width); it != cache.end()) return it->second;
  const auto& f = frames(width);
  frontend::TDetectorParams p;
  p.borderPx = 11;
  TFeatures out;
  for (const auto& c : frontend::detectInEmptyCells(f.a, {}, 30, p))
  {
    frontend::CFeaturePatch patch;
    if (!patch.extract(f.a, c.uv, 5)) continue;
    out.patches.push_back(patch);
    out.uv.push_back(c.uv);
  }
  return cache.emplace(width, out).first->second;
}

/** What both search benchmarks search with: the templates of the features found in the first
 * frame, and S = s^2 I whose 95 % ellipse has area `area` px^2 (pi * 5.991 * s^2). */
struct TSearchSetup
{
  std::vector<cv::Mat> templ;
  frontend::TSearchParams sp;
  Mat2 S = Mat2::Identity();
};
bool searchSetup(benchmark::State& st, int width, double area, TSearchSetup& out)
{
  const auto& feats = features(width);
  if (feats.patches.empty())
  {
    st.SkipWithError("no corners detected");
    return false;
  }
  for (const auto& p : feats.patches) out.templ.push_back(p.originalTemplate());
  out.S = Mat2::Identity() * (area / (kPi * out.sp.gateChi2));
  return true;
}

// One active search: ZNCC of an 11x11 template at every position of the 95 % ellipse of S, centred
// at the feature's pixel of the previous frame.
void BM_SearchInEllipse(benchmark::State& st)
{
  const int width = static_cast<int>(st.range(0));
  const auto& f = frames(width);
  const auto& feats = features(width);
  TSearchSetup su;
  if (!searchSetup(st, width, static_cast<double>(st.range(1)), su)) return;
  frontend::TSearchWorkspace ws;
  std::size_t k = 0, found = 0, searches = 0, evaluated = 0;
  for (auto _ : st)
  {
    const std::size_t i = k++ % su.templ.size();
    const auto res = frontend::searchInEllipse(f.b, su.templ[i], feats.uv[i], su.S, su.sp, ws);
    found += res.found ? 1 : 0;
    evaluated += res.evaluated;
    ++searches;
  }
  st.SetLabel(f.origin);
  st.counters["found_frac"] = static_cast<double>(found) / std::max<std::size_t>(searches, 1);
  st.counters["positions"] = static_cast<double>(evaluated) / std::max<std::size_t>(searches, 1);
}
BENCHMARK(BM_SearchInEllipse)
    ->ArgNames({"width", "area_px2"})
    ->ArgsProduct({{320, 640}, {100, 400, 1600, 6400}})
    ->Unit(benchmark::kMicrosecond);

// The same search through the allocation-per-call overload the filter uses today
// (CMonoSlamIMM::searchFeatures calls searchInEllipse without a workspace).
void BM_SearchInEllipseNoWorkspace(benchmark::State& st)
{
  const int width = static_cast<int>(st.range(0));
  const auto& f = frames(width);
  const auto& feats = features(width);
  TSearchSetup su;
  if (!searchSetup(st, width, static_cast<double>(st.range(1)), su)) return;
  std::size_t k = 0;
  for (auto _ : st)
  {
    const std::size_t i = k++ % su.templ.size();
    const auto res = frontend::searchInEllipse(f.b, su.templ[i], feats.uv[i], su.S, su.sp);
    benchmark::DoNotOptimize(res.score);
  }
  st.SetLabel(f.origin);
}
BENCHMARK(BM_SearchInEllipseNoWorkspace)
    ->ArgNames({"width", "area_px2"})
    ->ArgsProduct({{320, 640}, {100, 1600}})
    ->Unit(benchmark::kMicrosecond);

// Patch prediction (affine warp of the stored region: 20 deg rotation, 0.9 scale), per feature.
void BM_PredictTemplate(benchmark::State& st)
{
  const int width = static_cast<int>(st.range(0));
  const auto& feats = features(width);
  if (feats.patches.empty())
  {
    st.SkipWithError("no corners detected");
    return;
  }
  const double a = 20 * kPi / 180, s = 0.9;
  Mat2 A;
  A << s * std::cos(a), -s * std::sin(a), s * std::sin(a), s * std::cos(a);
  cv::Mat out;
  std::size_t k = 0;
  for (auto _ : st)
  {
    feats.patches[k++ % feats.patches.size()].predictTemplate(A, out);
    benchmark::DoNotOptimize(out.data);
  }
}
BENCHMARK(BM_PredictTemplate)->ArgName("width")->Arg(320)->Unit(benchmark::kMicrosecond);
}  // namespace

IMMSLAM_BENCHMARK_MAIN();
