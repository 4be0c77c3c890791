/* Tests of the synthetic-sequence renderer: scenario parsing, determinism, geometry (raycast,
 * masks, projections), camera motion (labels, smoothness), distortion, texture quality, outputs. */
#include <gtest/gtest.h>
#include <immslam/camera/CCameraModel.h>
#include <immslam/eval/classification_truth.h>
#include <immslam/math/quaternion.h>
#include <immslam/sim/CSimulator.h>
#include <immslam/sim/CSyntheticSource.h>
#include <immslam/sim/composite.h>
#include <immslam/sim/pixel_truth.h>
#include <immslam/sim/render_app.h>
#include <immslam/sim/rotated_view.h>
#include <immslam/camera/CPinholeCamera.h>
#include <immslam/io/CDatasetWriter.h>

#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <unistd.h>

using namespace immslam;
using namespace immslam::sim;
namespace fs = std::filesystem;

namespace
{
const std::vector<std::string> kShipped = {"default", "paper", "handheld", "handheld-moving"};

std::string scenarioPath(const std::string& name)
{
  return std::string(IMMSLAM_SOURCE_DIR) + "/ini/scenarios/" + name + ".ini";
}

/** Shipped scenarios, built once per test binary. */
const CSimulator& shipped(const std::string& name)
{
  static std::map<std::string, std::unique_ptr<CSimulator>> cache;
  auto& p = cache[name];
  if (!p) p = std::make_unique<CSimulator>(TScenario::loadFile(scenarioPath(name)));
  return *p;
}

std::unique_ptr<CSimulator> make(const std::string& name, const std::vector<std::string>& overrides)
{
  return std::make_unique<CSimulator>(TScenario::loadFile(scenarioPath(name), overrides));
}

bool identical(const cv::Mat& a, const cv::Mat& b)
{
  return a.size() == b.size() && a.type() == b.type() && (a.empty() || cv::norm(a, b, cv::NORM_INF) == 0);
}

std::string errorOf(const std::function<void()>& f)
{
  try
  {
    f();
  }
  catch (const std::exception& e)
  {
    return e.what();
  }
  return "(no exception)";
}

const char* kMinimal =
    "[scenario]\ncamera = pinhole 160 120 120 120 79.5 59.5\n[motion]\nsegments = general 1\n";

/** Temporary folder removed at scope exit. */
struct TTempDir
{
  fs::path path;
  explicit TTempDir(const std::string& tag)
      : path(fs::temp_directory_path() / ("immslam_sim_" + tag + "_" + std::to_string(::getpid())))
  {
    fs::remove_all(path);
  }
  ~TTempDir() { fs::remove_all(path); }
};

/** Exit status of an app's run function on args; its error output in `message`. */
int exitCode(int (*app)(const std::vector<std::string>&, std::ostream&, std::ostream&), const std::vector<std::string>& args,
             std::string& message)
{
  std::ostringstream o, e;
  const int rc = app(args, o, e);
  message = e.str();
  return rc;
}

std::vector<std::string> dataLines(const fs::path& p)
{
  std::ifstream f(p);
  std::vector<std::string> out;
  std::string l;
  while (std::getline(f, l))
    if (!l.empty() && l[0] != '#') out.push_back(l);
  return out;
}

bool projectW(const camera::CCameraModel& cam, const TPose& T_W_C, const Vec3& p_W, Vec2& uv, double* depth = nullptr)
{
  const Vec3 p_C = math::quatRotate(math::quatConjugate(T_W_C.q), p_W - T_W_C.t);
  if (depth) *depth = p_C.z();
  return p_C.z() > 1e-6 && cam.project(p_C, uv);
}

TPose toPose(const core::TStampedPose& s)
{
  TPose p;
  p.t = s.p_W_C;
  p.q = s.q_W_C;
  return p;
}
}  // namespace

// ---------------------------------------------------------------------------------------------
// Scenario files
// ---------------------------------------------------------------------------------------------

TEST(SimScenario, ShippedScenariosLoad)
{
  EXPECT_EQ(shipped("paper").frameCount(), 390u);
  EXPECT_EQ(shipped("paper").camera()->modelName(), "davison");
  EXPECT_EQ(shipped("handheld").frameCount(), 300u);
  EXPECT_EQ(shipped("handheld-moving").frameCount(), 300u);
  EXPECT_EQ(shipped("handheld-moving").world().movingObjects().size(), 3u);
  EXPECT_TRUE(shipped("handheld").world().movingObjects().empty());
  EXPECT_EQ(shipped("default").frameCount(), 180u);
  for (const auto& n : kShipped)
  {
    EXPECT_EQ(shipped(n).camera()->width(), 320) << n;
    EXPECT_EQ(shipped(n).camera()->height(), 240) << n;
    EXPECT_DOUBLE_EQ(shipped(n).scenario().fps, 30.0) << n;
    EXPECT_GE(shipped(n).world().staticBoxes().size(), 10u) << n;
  }
}

TEST(SimScenario, UnknownKeysSectionsAndBadValuesAreErrorsNamingThem)
{
  const std::string base = kMinimal;
  EXPECT_NE(errorOf([&] { TScenario::loadString(base + "segmnts = general 2\n", "t.ini"); }).find("segmnts"),
            std::string::npos);
  EXPECT_NE(errorOf([&] { TScenario::loadString(base + "[wrld]\nn_boxes = 3\n", "t.ini"); }).find("[wrld]"),
            std::string::npos);
  const std::string e1 = errorOf([&] { TScenario::loadString(base, "t.ini", {"scenario.fps=fast"}); });
  EXPECT_NE(e1.find("fps"), std::string::npos) << e1;
  EXPECT_NE(e1.find("t.ini"), std::string::npos) << e1;
  EXPECT_NE(errorOf([&] { TScenario::loadString(base, "t.ini", {"world.room_min=[1 2]"}); }).find("room_min"),
            std::string::npos);
  EXPECT_NE(errorOf([&] { TScenario::loadString(base, "t.ini", {"motion.segments=walking 2"}); }).find("walking"),
            std::string::npos);
  EXPECT_NE(errorOf([&] { TScenario::loadString("[motion]\nsegments = general 1\n", "t.ini"); }).find("camera"),
            std::string::npos);
  EXPECT_NE(errorOf([&] { TScenario::loadString(base + "[object1]\npath = zigzag\n", "t.ini"); }).find("path"),
            std::string::npos);
  EXPECT_NE(errorOf([&] { TScenario::loadString(base, "t.ini", {"bad-override"}); }).find("SECTION.KEY=VALUE"),
            std::string::npos);
  // Overrides and inline comments.
  const TScenario sc = TScenario::loadString(base + "[render]\nnoise_sigma_grey = 3 # grey levels\n", "t.ini",
                                             {"motion.segments=stationary 1, general 2", "scenario.seed=42"});
  EXPECT_EQ(sc.frameCount(), 90u);
  EXPECT_EQ(sc.seed, 42u);
  EXPECT_DOUBLE_EQ(sc.noise_sigma_grey, 3.0);
}

TEST(SimScenario, EveryScenarioFileUnderIniLoadsAndRenders)
{
  // The experiment scripts and the docs render every scenario under ini/scenarios (the hold-out
  // families included): each must load (no unknown key), show corners at its first and last frame,
  // and, when it has moving objects, mask some of them over its run.
  std::vector<fs::path> files;
  for (const auto& e : fs::recursive_directory_iterator(std::string(IMMSLAM_SOURCE_DIR) + "/ini/scenarios"))
    if (e.is_regular_file() && e.path().extension() == ".ini") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  ASSERT_GE(files.size(), 13u);
  for (const auto& f : files)
  {
    SCOPED_TRACE(f.string());
    std::unique_ptr<CSimulator> sim;
    ASSERT_NO_THROW(sim = std::make_unique<CSimulator>(TScenario::loadFile(f.string())));
    const std::size_t N = sim->frameCount();
    ASSERT_GE(N, 60u);
    for (const std::size_t k : {std::size_t{0}, N - 1})
    {
      std::vector<cv::KeyPoint> kp;
      cv::FAST(sim->render(k).grey, kp, 20, true);
      EXPECT_GE(kp.size(), 100u) << "frame " << k;
    }
    if (sim->world().movingObjects().empty()) continue;
    int masked = 0;
    for (std::size_t k = 0; k < N; k += 10) masked += cv::countNonZero(sim->renderMask(k)) > 0 ? 1 : 0;
    EXPECT_GT(masked, 0) << "no moving object masked in any tenth frame";
  }
}

TEST(SimScenario, EffectiveIniRoundTrips)
{
  for (const auto& n : kShipped)
  {
    const TScenario& sc = shipped(n).scenario();
    const TScenario back = TScenario::loadString(sc.toIni(), "scenario.ini");
    EXPECT_EQ(back.toIni(), sc.toIni()) << n;
  }
  // The round-tripped scenario renders the same images.
  const CSimulator again(TScenario::loadString(shipped("default").scenario().toIni(), "scenario.ini"));
  EXPECT_TRUE(identical(again.render(40).grey, shipped("default").render(40).grey));
}

TEST(SimScenario, BuiltinDefaultIsDefaultIni)
{
  EXPECT_EQ(TScenario::builtinDefault().toIni(), shipped("default").scenario().toIni());
  EXPECT_EQ(TScenario::builtinDefault({"scenario.seed=9"}).seed, 9u);
  CSyntheticSource src(TScenario::builtinDefault(), 2);
  io::TFrame f;
  std::string why;
  ASSERT_EQ(src.next(f, why), io::ENextStatus::Frame);
  EXPECT_TRUE(identical(f.grey, shipped("default").render(0).grey));
  EXPECT_NE(src.describe().find("built-in"), std::string::npos);
}

TEST(SimScenario, CameraPathOutsideFreeSpaceIsRejected)
{
  const std::string e = errorOf([] {
    CSimulator s(TScenario::loadString(kMinimal, "t.ini",
                                       {"world.room_min=[-1 -1 -1]", "world.room_max=[1 1 3]", "world.n_boxes=0",
                                        "motion.amplitude_units=[1.5 0 0]", "motion.max_speed_units_s=[10 1 1]",
                                        "motion.segments=general 20"}));
  });
  EXPECT_NE(e.find("min_clearance"), std::string::npos) << e;
}

// ---------------------------------------------------------------------------------------------
// Determinism
// ---------------------------------------------------------------------------------------------

TEST(SimDeterminism, SameSeedGivesIdenticalBytesWithAnyThreadCount)
{
  const auto a = make("handheld-moving", {"scenario.threads=1"});
  const auto& b = shipped("handheld-moving");  // 2 threads
  for (const std::size_t k : {0u, 77u, 299u})
  {
    const auto fa = a->render(k), fb = b.render(k);
    EXPECT_TRUE(identical(fa.grey, fb.grey)) << k;
    EXPECT_TRUE(identical(fa.mask, fb.mask)) << k;
    EXPECT_EQ(fa.T_W_C.p_W_C, fb.T_W_C.p_W_C);
  }
  const auto c = make("paper", {"render.colour=true", "scenario.threads=3"});
  const auto d = make("paper", {"render.colour=true"});
  const auto fc = c->render(200), fd = d->render(200);
  EXPECT_EQ(fc.colour.type(), CV_8UC3);
  EXPECT_TRUE(identical(fc.colour, fd.colour));
  EXPECT_TRUE(identical(fc.grey, fd.grey));
}

TEST(SimDeterminism, AnotherSeedGivesAnotherSequence)
{
  const auto other = make("default", {"scenario.seed=2"});
  const cv::Mat a = shipped("default").render(30).grey, b = other->render(30).grey;
  cv::Mat diff;
  cv::absdiff(a, b, diff);
  EXPECT_GT(cv::mean(diff)[0], 10.0);
  EXPECT_NE(shipped("default").cameraPose(60).p_W_C, other->cameraPose(60).p_W_C);
}

TEST(SimDeterminism, PixelNoiseHasTheConfiguredSigma)
{
  const auto clean = make("handheld", {"render.noise_sigma_grey=0"});
  const auto noisy = make("handheld", {"render.noise_sigma_grey=4"});
  cv::Mat a, b;
  clean->render(10).grey.convertTo(a, CV_32F);
  noisy->render(10).grey.convertTo(b, CV_32F);
  cv::Mat mean, sd;
  cv::meanStdDev(b - a, mean, sd);
  EXPECT_NEAR(mean.at<double>(0), 0.0, 0.1);
  EXPECT_NEAR(sd.at<double>(0), 4.0, 0.25);  // quantization adds ~1/12 grey^2
}

// ---------------------------------------------------------------------------------------------
// Geometry
// ---------------------------------------------------------------------------------------------

TEST(SimGeometry, KnownBoxPointsProjectWhereRaycastFindsThem)
{
  const CSimulator& sim = shipped("handheld-moving");
  const auto& cam = *sim.camera();
  int checked = 0, movingChecked = 0;
  for (const std::size_t k : {0u, 60u, 150u, 240u})
  {
    const TPose T_W_C = toPose(sim.cameraPose(k));
    for (const TBox& b : sim.world().boxesAt(sim.cameraTrajectory().time(k)))
    {
      if (b.inside) continue;
      for (int f = 0; f < 6; ++f)
      {
        const int a = f / 2, j = (a + 1) % 3, kk = (a + 2) % 3;
        for (const auto& st : {Vec2(0, 0), Vec2(0.9, 0.9), Vec2(-0.9, 0.9), Vec2(0.9, -0.9), Vec2(-0.9, -0.9)})
        {
          Vec3 p_B;
          p_B[a] = (f % 2 ? 1.0 : -1.0) * b.half[a];
          p_B[j] = st[0] * b.half[j];
          p_B[kk] = st[1] * b.half[kk];
          const Vec3 p_W = b.T_W_B.t + math::quatRotate(b.T_W_B.q, p_B);
          Vec2 uv;
          double depth = 0;
          if (!projectW(cam, T_W_C, p_W, uv, &depth) || !cam.isInImage(uv, 1.0)) continue;
          const auto hit = sim.raycast(k, uv);
          ASSERT_TRUE(hit.has_value());
          const double range = (p_W - T_W_C.t).norm();
          // Nothing lies beyond a surface along a ray: the hit is the point or an occluder.
          EXPECT_LE(hit->range, range + 1e-7);
          if (hit->surfaceId != b.firstSurface + f) continue;  // occluded or a back face
          EXPECT_LT((hit->p_W - p_W).norm(), 1e-7 * (1.0 + range));
          EXPECT_EQ(hit->objectId, b.objectId);
          EXPECT_NEAR(hit->depth, depth, 1e-7);
          ++checked;
          if (b.objectId) ++movingChecked;
        }
      }
    }
  }
  EXPECT_GE(checked, 40);
  EXPECT_GE(movingChecked, 5);
}

TEST(SimGeometry, RaycastRoundTripsThroughTheCameraModelAndDepth)
{
  for (const std::string n : {"paper", "handheld-moving"})
  {
    const CSimulator& sim = shipped(n);
    const auto& cam = *sim.camera();
    const std::size_t k = 100;
    const TPose T_W_C = toPose(sim.cameraPose(k));
    const cv::Mat depth = sim.renderDepth(k);
    for (int v = 3; v < cam.height(); v += 17)
      for (int u = 2; u < cam.width(); u += 19)
      {
        const auto hit = sim.raycast(k, Vec2(u, v));
        ASSERT_TRUE(hit.has_value());
        EXPECT_GT(hit->depth, 0.2);
        EXPECT_NEAR(depth.at<float>(v, u), hit->depth, 1e-5 * hit->depth);
        Vec2 uv;
        ASSERT_TRUE(projectW(cam, T_W_C, hit->p_W, uv));
        EXPECT_LT((uv - Vec2(u, v)).norm(), 1e-6) << n << " " << u << "," << v;
      }
  }
}

TEST(SimGeometry, MasksAgreeWithRaycastAndObjectPoses)
{
  const CSimulator& sim = shipped("handheld-moving");
  std::size_t objectPixels = 0;
  for (const std::size_t k : {0u, 90u, 200u})
  {
    const cv::Mat mask = sim.renderMask(k);
    EXPECT_TRUE(identical(mask, sim.render(k).mask));
    const auto poses = sim.objectPoses(k);
    for (int v = 0; v < mask.rows; v += 2)
      for (int u = 0; u < mask.cols; u += 2)
      {
        const auto hit = sim.raycast(k, Vec2(u, v));
        ASSERT_TRUE(hit.has_value());
        const int id = mask.at<std::uint8_t>(v, u);
        ASSERT_EQ(hit->objectId, id) << "frame " << k << " pixel " << u << "," << v;
        if (id == 0) continue;
        ++objectPixels;
        // The hit lies on the surface of object `id` at its ground-truth pose.
        const auto it = std::find_if(poses.begin(), poses.end(), [&](const TObjectPose& p) { return p.id == id; });
        ASSERT_NE(it, poses.end());
        const auto& spec = *std::find_if(sim.world().movingObjects().begin(), sim.world().movingObjects().end(),
                                         [&](const TMovingObjectSpec& o) { return o.id == id; });
        const Vec3 p_O = math::quatRotate(math::quatConjugate(it->T_W_O.q), hit->p_W - it->T_W_O.t);
        EXPECT_NEAR((p_O.cwiseAbs() - 0.5 * spec.size).maxCoeff(), 0.0, 1e-9);
      }
  }
  EXPECT_GT(objectPixels, 1000u);
}

TEST(SimGeometry, TruthAtTrackedPixelsIsTheSurfacePointSeenThere)
{
  // Samples at object interiors, static interiors, silhouettes and a time with no frame: the truth
  // returned is the ray-cast point (scored at 0 error when the estimate is exact), the kinds are
  // the mask's, silhouettes are left out, and trackErrorAgainstPoints() joins each row to its own truth.
  const CSimulator& sim = shipped("handheld-moving");
  const std::size_t k = 90;
  const cv::Mat mask = sim.renderMask(k);
  cv::Mat inner, outer;
  cv::erode(mask > 0, inner, cv::Mat::ones(9, 9, CV_8U));  // 4 px inside an object
  cv::erode(mask == 0, outer, cv::Mat::ones(9, 9, CV_8U));
  std::vector<core::TTrackSample> samples;
  std::vector<int> kind;  // 1 moving, 0 static, 2 silhouette
  for (int v = 10; v < mask.rows - 10; v += 7)
    for (int u = 10; u < mask.cols - 10; u += 7)
    {
      const bool edge = mask.at<std::uint8_t>(v, u) != mask.at<std::uint8_t>(v, u + 1);
      const int c = inner.at<std::uint8_t>(v, u) ? 1 : outer.at<std::uint8_t>(v, u) ? 0 : edge ? 2 : -1;
      if (c < 0) continue;
      core::TTrackSample t;
      t.timestamp = sim.timestamp(k) + 1e-6;
      t.featureId = static_cast<std::int64_t>(samples.size());
      t.uv = Vec2(u + 0.3, v + 0.6);
      samples.push_back(t);
      kind.push_back(c);
    }
  core::TTrackSample late = samples.front();
  late.timestamp = sim.timestamp(k) + 0.5 / sim.scenario().fps;  // half-way between two frames
  samples.push_back(late);
  kind.push_back(3);

  TPixelTruthStats st;
  const auto truth = truthAtPixels(sim, samples, 1e-4, 2.0, 0.05, &st);
  EXPECT_EQ(st.samples, samples.size());
  EXPECT_EQ(st.noFrame, 1u);
  const auto count = [&](int c) { return static_cast<std::size_t>(std::count(kind.begin(), kind.end(), c)); };
  EXPECT_GT(count(1), 10u);
  EXPECT_EQ(st.onMoving, count(1));
  EXPECT_GE(st.boundary, count(2));  // every silhouette sample is left out
  EXPECT_GE(st.onStatic, count(0) * 9 / 10);  // static interiors (a few are near a depth step of the room)
  ASSERT_EQ(truth.size(), st.onMoving + st.onStatic);
  for (const auto& g : truth)
  {
    const std::size_t s = static_cast<std::size_t>(g.pointId);
    EXPECT_NE(kind[s], 2);
    EXPECT_EQ(g.moving, kind[s] == 1);
    const auto hit = sim.raycast(k, samples[s].uv);
    ASSERT_TRUE(hit.has_value());
    EXPECT_EQ((g.p_W - hit->p_W).norm(), 0.0);
    samples[s].p_W = hit->p_W;  // a perfect tracker
  }
  const eval::TTrackErrorResult r = eval::trackErrorAgainstPoints(samples, truth, eval::TSim3{}, 0.5);
  EXPECT_EQ(r.matched, st.onMoving);
  EXPECT_EQ(r.onStatic, st.onStatic);
  EXPECT_NEAR(r.rmse, 0.0, 1e-12);

  // A folder without scenario.ini is refused naming it.
  EXPECT_NE(errorOf([&] { truthAtPixelsOfRenderedFolder("/nonexistent-folder", samples); }).find("/nonexistent-folder"),
            std::string::npos);
}

TEST(SimGeometry, MovingObjectsCoverAFewToAThirdOfTheImage)
{
  const CSimulator& sim = shipped("handheld-moving");
  double maxFrac = 0, sumFrac = 0;
  int n = 0;
  for (std::size_t k = 0; k < sim.frameCount(); k += 10, ++n)
  {
    const cv::Mat m = sim.renderMask(k);
    const double f = cv::countNonZero(m) / static_cast<double>(m.total());
    maxFrac = std::max(maxFrac, f);
    sumFrac += f;
  }
  EXPECT_GT(maxFrac, 0.10);
  EXPECT_LT(maxFrac, 0.35);
  EXPECT_GT(sumFrac / n, 0.05);
}

// ---------------------------------------------------------------------------------------------
// Camera motion
// ---------------------------------------------------------------------------------------------

TEST(SimMotion, LabelsAreTheTrueMotion)
{
  for (const auto& n : kShipped)
  {
    const auto& tr = shipped(n).cameraTrajectory();
    EXPECT_EQ(tr.label(0), EMotionLabel::Stationary);
    for (std::size_t k = 1; k < tr.size(); ++k)
    {
      const TPose &a = tr.pose(k - 1), &b = tr.pose(k);
      switch (tr.label(k))
      {
        case EMotionLabel::Stationary:
          EXPECT_TRUE(a.t == b.t && a.q == b.q) << n << " frame " << k;
          break;
        case EMotionLabel::Rotation:
          EXPECT_TRUE(a.t == b.t) << n << " frame " << k;
          EXPECT_GT((a.q - b.q).norm(), 1e-9) << n << " frame " << k;
          break;
        case EMotionLabel::General:
          EXPECT_GT((a.t - b.t).norm(), 1e-9) << n << " frame " << k;
          break;
      }
    }
  }
}

TEST(SimMotion, PaperScriptGivesThePapersSequenceShape)
{
  const auto& tr = shipped("paper").cameraTrajectory();
  std::vector<std::pair<EMotionLabel, int>> runs;
  for (std::size_t k = 0; k < tr.size(); ++k)
  {
    if (runs.empty() || runs.back().first != tr.label(k)) runs.push_back({tr.label(k), 0});
    ++runs.back().second;
  }
  const std::vector<std::pair<EMotionLabel, int>> expected = {{EMotionLabel::Stationary, 61},
                                                              {EMotionLabel::Rotation, 90},
                                                              {EMotionLabel::General, 120},
                                                              {EMotionLabel::Rotation, 60},
                                                              {EMotionLabel::Stationary, 59}};
  EXPECT_EQ(runs, expected);
  // Rotation segments really rotate: at least ~5 degrees each.
  EXPECT_GT(2 * std::acos(std::min(1.0, std::abs(tr.pose(61).q.dot(tr.pose(150).q)))), 5 * M_PI / 180);
  EXPECT_GT(2 * std::acos(std::min(1.0, std::abs(tr.pose(271).q.dot(tr.pose(330).q)))), 5 * M_PI / 180);
  EXPECT_GT((tr.pose(151).t - tr.pose(270).t).norm(), 0.05);
}

TEST(SimMotion, VelocitiesAndAccelerationsAreBounded)
{
  for (const auto& n : kShipped)
  {
    const CSimulator& sim = shipped(n);
    const auto& tr = sim.cameraTrajectory();
    const auto& sc = sim.scenario();
    const double fps = sc.fps;
    const double maxSpeed = sc.max_speed_units_s.norm(), maxRate = sc.max_rate_deg_s.norm() * M_PI / 180;
    double aMax = 0, alphaMax = 0, vMax = 0, wMax = 0;
    for (std::size_t k = 1; k + 1 < tr.size(); ++k)
    {
      const double t = tr.time(k);
      vMax = std::max(vMax, tr.linearVelocity(t).norm());
      wMax = std::max(wMax, tr.angularVelocity(t).norm());
      aMax = std::max(aMax, ((tr.pose(k + 1).t - 2 * tr.pose(k).t + tr.pose(k - 1).t) * fps * fps).norm());
      alphaMax = std::max(alphaMax, (tr.angularVelocity(tr.time(k + 1)) - tr.angularVelocity(t)).norm() * fps);
    }
    EXPECT_LE(vMax, maxSpeed * 1.001) << n;
    EXPECT_LE(wMax, maxRate * 1.05) << n;
    EXPECT_GT(vMax, 0.1) << n;
    EXPECT_GT(wMax, 5 * M_PI / 180) << n;
    EXPECT_LT(aMax, 4.0) << n;      // units/s^2
    EXPECT_LT(alphaMax, 4.0) << n;  // rad/s^2
    // The camera stays in the room's free space.
    for (std::size_t k = 0; k < tr.size(); ++k) ASSERT_TRUE(sim.world().isFree(tr.pose(k).t, sc.min_clearance));
  }
}

TEST(SimMotion, VelocitiesAreTheDerivativesOfThePoses)
{
  const auto& tr = shipped("paper").cameraTrajectory();
  const double h = 1e-5;
  for (double t = 0.05; t < 13.0; t += 0.37)
  {
    const TPose a = tr.poseAt(t - h), b = tr.poseAt(t + h);
    const Vec3 v = (b.t - a.t) / (2 * h);
    const Vec3 w = math::quatToRotationVector(math::quatMultiply(math::quatConjugate(a.q), b.q)) / (2 * h);
    EXPECT_LT((v - tr.linearVelocity(t)).norm(), 1e-6) << t;
    EXPECT_LT((w - tr.angularVelocity(t)).norm(), 1e-6) << t;
  }
}

TEST(SimMotion, MovingObjectsChangeNeitherTheCameraPathNorTheStaticWorld)
{
  const CSimulator& still = shipped("handheld");
  const CSimulator& moving = shipped("handheld-moving");
  ASSERT_EQ(still.frameCount(), moving.frameCount());
  for (std::size_t k = 0; k < still.frameCount(); ++k)
  {
    ASSERT_EQ(still.cameraPose(k).p_W_C, moving.cameraPose(k).p_W_C);
    ASSERT_EQ(still.cameraPose(k).q_W_C, moving.cameraPose(k).q_W_C);
  }
  for (const std::size_t k : {0u, 120u})
  {
    const auto a = still.render(k), b = moving.render(k);
    cv::Mat diff, staticPx;
    cv::absdiff(a.grey, b.grey, diff);
    cv::compare(b.mask, 0, staticPx, cv::CMP_EQ);
    double maxStatic = 0;
    cv::minMaxLoc(diff, nullptr, &maxStatic, nullptr, nullptr, staticPx);
    EXPECT_EQ(maxStatic, 0.0) << k;
    EXPECT_GT(cv::countNonZero(b.mask), 500) << k;
  }
}

// ---------------------------------------------------------------------------------------------
// Distortion
// ---------------------------------------------------------------------------------------------

TEST(SimDistortion, EveryPixelsRayIsTheModelsUnprojection)
{
  const CSimulator& sim = shipped("paper");
  const auto& cam = *sim.camera();
  for (int v = 0; v < cam.height(); v += 7)
    for (int u = 0; u < cam.width(); u += 5)
      ASSERT_EQ(sim.renderer().bearing(u, v), cam.unproject(Vec2(u, v)).unitVector()) << u << "," << v;
  // The wide-angle model bends rays: corner rays are far wider than a pinhole's with the same f.
  const Vec3 b = sim.renderer().bearing(0, 0);
  EXPECT_GT(std::abs(b.x() / b.z()), 1.2 * (cam.cx() / cam.fx()));
}

TEST(SimDistortion, DavisonRenderEqualsTheRemappedPinholeRender)
{
  const auto dav = make("paper", {"render.noise_sigma_grey=0"});
  const auto& dc = *dav->camera();
  // A pinhole camera with the same focal length and a field of view covering the davison image.
  double maxX = 0, maxY = 0;
  for (int u = 0; u < dc.width(); ++u)
    for (const int v : {0, dc.height() - 1})
    {
      const Vec3 b = dc.unproject(Vec2(u, v)).unitVector();
      maxX = std::max(maxX, std::abs(b.x() / b.z()));
      maxY = std::max(maxY, std::abs(b.y() / b.z()));
    }
  for (int v = 0; v < dc.height(); ++v)
    for (const int u : {0, dc.width() - 1})
    {
      const Vec3 b = dc.unproject(Vec2(u, v)).unitVector();
      maxX = std::max(maxX, std::abs(b.x() / b.z()));
      maxY = std::max(maxY, std::abs(b.y() / b.z()));
    }
  const int W = 2 * static_cast<int>(std::ceil(dc.fx() * maxX)) + 4, H = 2 * static_cast<int>(std::ceil(dc.fy() * maxY)) + 4;
  std::ostringstream line;
  line << "pinhole " << W << " " << H << " " << dc.fx() << " " << dc.fy() << " " << (W - 1) / 2.0 << " " << (H - 1) / 2.0;
  const auto pin = make("paper", {"render.noise_sigma_grey=0", "scenario.camera=" + line.str()});
  for (const std::size_t k : {0u, 200u})
  {
    const cv::Mat d = dav->render(k).grey, p = pin->render(k).grey;
    cv::Mat mapX(d.size(), CV_32F), mapY(d.size(), CV_32F);
    for (int v = 0; v < d.rows; ++v)
      for (int u = 0; u < d.cols; ++u)
      {
        Vec2 uv;
        ASSERT_TRUE(pin->camera()->project(dc.unproject(Vec2(u, v)).unitVector(), uv));
        mapX.at<float>(v, u) = static_cast<float>(uv.x());
        mapY.at<float>(v, u) = static_cast<float>(uv.y());
      }
    cv::Mat remapped, diff;
    cv::remap(p, remapped, mapX, mapY, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
    cv::absdiff(remapped, d, diff);
    // Differences come from resampling and from mip levels chosen for different pixel sizes.
    EXPECT_LT(cv::mean(diff)[0], 8.0) << k;
    cv::Mat df, rf;
    d.convertTo(df, CV_32F);
    remapped.convertTo(rf, CV_32F);
    cv::Mat c;
    cv::matchTemplate(df, rf, c, cv::TM_CCOEFF_NORMED);
    EXPECT_GT(c.at<float>(0, 0), 0.85) << k;
  }
}

// ---------------------------------------------------------------------------------------------
// Texture quality
// ---------------------------------------------------------------------------------------------

TEST(SimTexture, EnoughWellSpreadFastCornersInEveryShippedScenario)
{
  for (const auto& n : kShipped)
  {
    const CSimulator& sim = shipped(n);
    const std::size_t N = sim.frameCount();
    for (const std::size_t k : {std::size_t{0}, N / 3, N / 2, (2 * N) / 3, N - 1})
    {
      const cv::Mat g = sim.render(k).grey;
      std::vector<cv::KeyPoint> kp;
      cv::FAST(g, kp, 20, true);
      bool cell[6][8] = {};
      for (const auto& p : kp) cell[std::min(5, static_cast<int>(p.pt.y * 6 / g.rows))][std::min(7, static_cast<int>(p.pt.x * 8 / g.cols))] = true;
      int covered = 0;
      for (const auto& r : cell)
        for (const bool c : r) covered += c;
      EXPECT_GE(kp.size(), 100u) << n << " frame " << k;
      EXPECT_GE(covered, 34) << n << " frame " << k << " (>= 70 % of 8x6 cells)";
    }
  }
}

TEST(SimTexture, PatchesAreFoundAgainByNormalizedCrossCorrelation)
{
  // Ground-truth tracking: an 11x11 patch around a FAST corner in frame k is searched in frame k+3
  // around where the true 3-D point projects; the best NCC match must be at the true position.
  const CSimulator& sim = shipped("handheld");
  const auto& cam = *sim.camera();
  int tried = 0, good = 0;
  for (const std::size_t k : {20u, 100u, 200u})
  {
    const cv::Mat a = sim.render(k).grey, b = sim.render(k + 3).grey;
    std::vector<cv::KeyPoint> kp;
    cv::FAST(a, kp, 25, true);
    cv::KeyPointsFilter::retainBest(kp, 60);
    const TPose T1 = toPose(sim.cameraPose(k + 3));
    for (const auto& p : kp)
    {
      const Vec2 uv(std::round(p.pt.x), std::round(p.pt.y));
      const auto hit = sim.raycast(k, uv);
      Vec2 uv1;
      if (!hit || !projectW(cam, T1, hit->p_W, uv1) || !cam.isInImage(uv, 6) || !cam.isInImage(uv1, 20)) continue;
      const auto again = sim.raycast(k + 3, uv1);  // skip points occluded in frame k+3
      if (!again || (again->p_W - hit->p_W).norm() > 1e-3 * hit->range) continue;
      const cv::Mat patch = a(cv::Rect(static_cast<int>(uv.x()) - 5, static_cast<int>(uv.y()) - 5, 11, 11));
      const int cx = static_cast<int>(std::round(uv1.x())), cy = static_cast<int>(std::round(uv1.y()));
      const cv::Mat search = b(cv::Rect(cx - 15, cy - 15, 31, 31));
      cv::Mat score;
      cv::matchTemplate(search, patch, score, cv::TM_CCOEFF_NORMED);
      cv::Point best;
      cv::minMaxLoc(score, nullptr, nullptr, nullptr, &best);
      const Vec2 found(cx - 15 + best.x + 5, cy - 15 + best.y + 5);
      ++tried;
      if ((found - uv1).norm() < 1.5) ++good;
    }
  }
  ASSERT_GT(tried, 60);
  EXPECT_GT(good, 0.85 * tried) << good << " / " << tried;
}

// ---------------------------------------------------------------------------------------------
// Outputs
// ---------------------------------------------------------------------------------------------

TEST(SimOutput, DatasetFolderHasEveryFileAndReadsBack)
{
  const CSimulator& sim = shipped("handheld-moving");
  TTempDir dir("dataset");
  const std::size_t n = 6;
  const TWriteStats st = sim.writeDataset(dir.path.string(), n);
  EXPECT_EQ(st.frames, n);
  EXPECT_EQ(dataLines(dir.path / "rgb.txt").size(), n);
  EXPECT_EQ(dataLines(dir.path / "groundtruth.txt").size(), n);
  EXPECT_EQ(dataLines(dir.path / "motion_labels.txt").size(), n);
  EXPECT_EQ(dataLines(dir.path / "camera_velocity.txt").size(), n);
  EXPECT_EQ(dataLines(dir.path / "objects_groundtruth.txt").size(), 3 * n);
  EXPECT_EQ(dataLines(dir.path / "world_boxes.txt").size(), 1 + sim.world().staticBoxes().size() + 3);
  EXPECT_EQ(dataLines(dir.path / "motion_labels.txt")[1].substr(9), "general");
  for (const auto& f : {"rgb.txt", "groundtruth.txt", "motion_labels.txt", "objects_groundtruth.txt", "camera_velocity.txt",
                        "world_boxes.txt"})
  {
    std::ifstream in(dir.path / f);
    std::string first;
    std::getline(in, first);
    EXPECT_EQ(first.substr(0, 1), "#") << f;
  }
  // Images and masks read back bit-exactly; the object poses line up with the frames.
  const auto rgb = dataLines(dir.path / "rgb.txt");
  for (std::size_t k = 0; k < n; ++k)
  {
    std::istringstream is(rgb[k]);
    double ts;
    std::string rel;
    is >> ts >> rel;
    EXPECT_NEAR(ts, sim.timestamp(k), 1e-6);
    const auto f = sim.render(k);
    EXPECT_TRUE(identical(cv::imread((dir.path / rel).string(), cv::IMREAD_UNCHANGED), f.grey)) << rel;
    EXPECT_TRUE(identical(cv::imread((dir.path / "masks" / fs::path(rel).filename()).string(), cv::IMREAD_UNCHANGED), f.mask));
  }
  std::istringstream o(dataLines(dir.path / "objects_groundtruth.txt")[4]);
  double ts, q[7];
  int id;
  o >> ts >> id;
  for (double& x : q) o >> x;
  EXPECT_NEAR(ts, sim.timestamp(1), 1e-6);
  const auto poses = sim.objectPoses(1);
  EXPECT_EQ(id, poses[1].id);
  EXPECT_NEAR(q[0], poses[1].T_W_O.t.x(), 1e-8);
  EXPECT_NEAR(q[6], poses[1].T_W_O.q[0], 1e-8);  // qw last
  // Calibration and the effective scenario reload.
  EXPECT_EQ(camera::loadCalibFile((dir.path / "calib.txt").string())->toCalibLine(), sim.camera()->toCalibLine());
  EXPECT_EQ(TScenario::loadFile((dir.path / "scenario.ini").string()).toIni(), sim.scenario().toIni());
}

TEST(SimOutput, RenderAppCommandLine)
{
  TTempDir dir("app");
  std::ostringstream out, err;
  const std::string sc = scenarioPath("default");
  EXPECT_EQ(runRenderApp({sc, dir.path.string(), "--frames", "3", "--seed", "5", "--set", "render.noise_sigma_grey=0"}, out, err), 0)
      << err.str();
  EXPECT_NE(out.str().find("wrote 3 frames"), std::string::npos) << out.str();
  EXPECT_EQ(dataLines(dir.path / "rgb.txt").size(), 3u);
  const TScenario written = TScenario::loadFile((dir.path / "scenario.ini").string());
  EXPECT_EQ(written.seed, 5u);
  EXPECT_EQ(written.noise_sigma_grey, 0.0);

  std::ostringstream o2, e2;
  EXPECT_EQ(runRenderApp({"--help"}, o2, e2), 0);
  EXPECT_NE(o2.str().find("Usage"), std::string::npos);
  EXPECT_EQ(runRenderApp({}, o2, e2), 2);
  EXPECT_EQ(runRenderApp({sc, dir.path.string(), "--bogus"}, o2, e2), 2);
  EXPECT_EQ(runRenderApp({sc, dir.path.string(), "--frames", "x"}, o2, e2), 2);
  std::ostringstream o3, e3;
  EXPECT_EQ(runRenderApp({sc, dir.path.string(), "--set", "motion.bogus_key=1"}, o3, e3), 1);
  EXPECT_NE(e3.str().find("bogus_key"), std::string::npos) << e3.str();
  EXPECT_EQ(runRenderApp({"/nonexistent/scenario.ini", dir.path.string()}, o3, e3), 1);
}

TEST(SimOutput, PointTracksAreTheVisibleProjectionsOfPointsOnTheirSurfaces)
{
  // CSimulator::writePointTracks (imm-render --points): the known-association input of Fig. 5.
  const CSimulator& sim = shipped("handheld-moving");
  TTempDir dir("points");
  fs::create_directories(dir.path);
  const std::size_t n = 60;
  TPointTrackOptions o;
  o.staticPoints = 150;
  o.pointsPerObject = 10;
  o.noisePx = 0;
  const std::string exact = (dir.path / "exact.txt").string();
  const std::size_t rows = sim.writePointTracks(exact, n, o);
  struct TRow
  {
    double t;
    long id;
    std::string kind;
    Vec3 p;
    Vec2 uv;
  };
  const auto read = [](const std::string& path) {
    std::vector<TRow> out;
    for (const auto& l : dataLines(path))
    {
      std::istringstream is(l);
      TRow r;
      is >> r.t >> r.id >> r.kind >> r.p.x() >> r.p.y() >> r.p.z() >> r.uv.x() >> r.uv.y();
      EXPECT_FALSE(is.fail()) << l;
      out.push_back(r);
    }
    return out;
  };
  const auto tracks = read(exact);
  ASSERT_EQ(tracks.size(), rows);
  std::map<long, Vec3> inObjectFrame;  // a point keeps its place on its object (static: in the world)
  std::map<std::size_t, cv::Mat> masks;
  std::size_t agree = 0, moving = 0;
  std::vector<std::size_t> perFrame(n, 0);
  for (const auto& r : tracks)
  {
    const auto k = static_cast<std::size_t>(std::lround((r.t - sim.timestamp(0)) * sim.scenario().fps));
    ASSERT_LT(k, n);
    ASSERT_NEAR(sim.timestamp(k), r.t, 1e-6);
    ++perFrame[k];
    // (u, v) is the projection of (x, y, z) by the camera at its true pose (no noise asked).
    const auto T = sim.cameraPose(k);
    const Vec3 p_C = math::quatRotate(math::quatConjugate(T.q_W_C), r.p - T.p_W_C);
    Vec2 uv;
    ASSERT_TRUE(sim.camera()->project(p_C, uv));
    EXPECT_NEAR((uv - r.uv).norm(), 0.0, 1e-3);
    // The point is the first thing its ray hits (not occluded), on the right kind of surface.
    const auto hit = sim.raycast(k, r.uv);
    ASSERT_TRUE(hit.has_value());
    EXPECT_EQ(hit->objectId != 0, r.kind == "moving");
    EXPECT_NEAR((hit->p_W - r.p).norm(), 0.0, 1e-3 * hit->range);
    Vec3 local = r.p;
    if (r.kind == "moving")
    {
      ++moving;
      const auto poses = sim.objectPoses(k);
      const auto it = std::find_if(poses.begin(), poses.end(), [&](const TObjectPose& q) { return q.id == hit->objectId; });
      ASSERT_NE(it, poses.end());
      local = math::quatRotate(math::quatConjugate(it->T_W_O.q), r.p - it->T_W_O.t);
    }
    const auto [pos, fresh] = inObjectFrame.emplace(r.id, local);
    if (!fresh)
    {
      EXPECT_NEAR((pos->second - local).norm(), 0.0, 1e-5) << "point " << r.id;
    }
    // The renderer's mask says the same (away from silhouettes: almost everywhere).
    if (!masks.count(k)) masks[k] = sim.renderMask(k);
    const int u = std::clamp(static_cast<int>(std::lround(r.uv.x())), 0, masks[k].cols - 1);
    const int v = std::clamp(static_cast<int>(std::lround(r.uv.y())), 0, masks[k].rows - 1);
    agree += (masks[k].at<std::uint8_t>(v, u) != 0) == (r.kind == "moving") ? 1 : 0;
  }
  EXPECT_GE(agree, 0.98 * tracks.size());
  EXPECT_GT(moving, 0u);
  EXPECT_GE(*std::min_element(perFrame.begin(), perFrame.end()), 30u);
  // With noise: the same points, each projection displaced by N(0, sigma^2) per coordinate.
  o.noisePx = 0.5;
  const std::string noisy = (dir.path / "noisy.txt").string();
  const std::size_t noisyRows = sim.writePointTracks(noisy, n, o);
  EXPECT_GE(noisyRows, 0.99 * rows);  // a few leave the image
  EXPECT_LE(noisyRows, rows);
  std::map<std::pair<long, long>, Vec2> exactAt;
  for (const auto& r : tracks) exactAt[{std::lround(r.t * 1e6), r.id}] = r.uv;
  const auto withNoise = read(noisy);
  double ss = 0;
  for (const auto& r : withNoise)
  {
    const auto it = exactAt.find({std::lround(r.t * 1e6), r.id});
    ASSERT_NE(it, exactAt.end());
    ss += (r.uv - it->second).squaredNorm();
  }
  EXPECT_NEAR(std::sqrt(ss / (2.0 * withNoise.size())), 0.5, 0.05);
  // The command line.
  std::ostringstream out, err;
  const std::string sc = scenarioPath("handheld-moving");
  EXPECT_EQ(runRenderApp({sc, (dir.path / "app").string(), "--frames", "5", "--points", "40,6"}, out, err), 0) << err.str();
  EXPECT_TRUE(std::filesystem::exists(dir.path / "app" / "points_groundtruth.txt"));
  EXPECT_EQ(runRenderApp({sc, (dir.path / "bad").string(), "--points", "x"}, out, err), 2);
  EXPECT_EQ(runRenderApp({sc, (dir.path / "bad").string(), "--points", "10,-1"}, out, err), 2);
  EXPECT_EQ(runRenderApp({sc, (dir.path / "bad").string(), "--point-noise", "-1"}, out, err), 2);
}

TEST(SimOutput, SyntheticSourceStreamsTheScenario)
{
  CSyntheticSource src(scenarioPath("handheld-moving"), {}, 5);
  EXPECT_EQ(src.sizeHint(), 5u);
  ASSERT_TRUE(src.calibration());
  EXPECT_EQ(src.calibration()->modelName(), "pinhole");
  ASSERT_TRUE(src.groundTruth().has_value());
  EXPECT_EQ(src.groundTruth()->size(), 5u);
  EXPECT_NE(src.describe().find("handheld-moving"), std::string::npos);
  const CSimulator& sim = shipped("handheld-moving");
  io::TFrame f;
  std::string why;
  for (std::size_t k = 0; k < 5; ++k)
  {
    ASSERT_EQ(src.next(f, why), io::ENextStatus::Frame);
    EXPECT_EQ(f.index, k);
    EXPECT_DOUBLE_EQ(f.timestamp, sim.timestamp(k));
    EXPECT_TRUE(identical(f.grey, sim.render(k).grey));
    EXPECT_TRUE(identical(src.mask(k), sim.renderMask(k)));
    EXPECT_EQ(src.label(k), sim.motionLabel(k));
    EXPECT_EQ(src.objectPoses(k).size(), 3u);
  }
  EXPECT_TRUE(identical(src.mask(1), sim.renderMask(1)));
  EXPECT_EQ(src.next(f, why), io::ENextStatus::End);
}

TEST(SimComposite, PastedObjectFollowsItsPathAndTheMaskIsItsTruth)
{
  TTempDir src("composite_src"), dst("composite_dst");
  std::ostringstream out, err;
  ASSERT_EQ(runRenderApp({scenarioPath("default"), src.path.string(), "--frames", "8", "--set", "render.noise_sigma_grey=0"}, out, err), 0)
      << err.str();
  // A texture whose every pixel is known: a horizontal ramp.
  cv::Mat tex(30, 40, CV_8UC1);
  for (int y = 0; y < tex.rows; ++y)
    for (int x = 0; x < tex.cols; ++x) tex.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(40 + 5 * x);
  const std::string texPath = (src.path / "texture.png").string();
  ASSERT_TRUE(cv::imwrite(texPath, tex));

  TCompositeObject o;
  o.image = texPath;
  o.from = Vec2(20, 50);
  o.to = Vec2(140, 70);
  o.firstFrame = 2;
  o.lastFrame = 6;
  o.scaleFirst = o.scaleLast = 1.0;
  const TCompositeStats st = compositeMovingObjects(src.path.string(), dst.path.string(), {o});
  EXPECT_EQ(st.frames, 8u);
  EXPECT_EQ(st.skipped, 0u);
  EXPECT_EQ(st.objectFrames, 5u);
  const auto rgbIn = dataLines(src.path / "rgb.txt"), rgbOut = dataLines(dst.path / "rgb.txt");
  ASSERT_EQ(rgbOut.size(), 8u);
  for (const char* f : {"calib.txt", "groundtruth.txt"})
  {
    std::ifstream a(src.path / f), b(dst.path / f);
    EXPECT_EQ(std::string(std::istreambuf_iterator<char>(a), {}), std::string(std::istreambuf_iterator<char>(b), {})) << f;
  }
  const auto centres = dataLines(dst.path / "objects.txt");
  ASSERT_EQ(centres.size(), 5u);
  for (std::size_t k = 0; k < 8; ++k)
  {
    std::istringstream a(rgbIn[k]), b(rgbOut[k]);
    double ta, tb;
    std::string ra, rb;
    a >> ta >> ra;
    b >> tb >> rb;
    EXPECT_NEAR(ta, tb, 1e-6);
    const cv::Mat in = cv::imread((src.path / ra).string(), cv::IMREAD_UNCHANGED);
    const cv::Mat img = cv::imread((dst.path / rb).string(), cv::IMREAD_UNCHANGED);
    const cv::Mat mask = cv::imread((dst.path / "masks" / fs::path(rb).filename()).string(), cv::IMREAD_UNCHANGED);
    ASSERT_EQ(img.type(), CV_8UC1) << "a grey source gives grey frames";
    ASSERT_EQ(mask.type(), CV_8UC1);
    if (k < 2 || k > 6)
    {
      EXPECT_TRUE(identical(img, in)) << "frame " << k << " has no object";
      EXPECT_EQ(cv::countNonZero(mask), 0);
      continue;
    }
    // The centre moves linearly from `from` to `to` over the span.
    std::istringstream c(centres[k - 2]);
    double ts, u, v, scale;
    int id;
    c >> ts >> id >> u >> v >> scale;
    EXPECT_NEAR(ts, ta, 1e-6);
    EXPECT_EQ(id, 1);
    const Vec2 expected = o.from + (static_cast<double>(k) - 2.0) / 4.0 * (o.to - o.from);
    EXPECT_NEAR(u, expected.x(), 1e-3);
    EXPECT_NEAR(v, expected.y(), 1e-3);
    // The mask is the ellipse inscribed in the 40x30 crop (area pi 20 15), object id 1.
    EXPECT_NEAR(cv::countNonZero(mask), M_PI * 20 * 15, 0.04 * M_PI * 20 * 15);
    double maxVal = 0;
    cv::minMaxLoc(mask, nullptr, &maxVal);
    EXPECT_EQ(maxVal, 1.0);
    for (int y = 0; y < img.rows; ++y)
      for (int x = 0; x < img.cols; ++x)
      {
        const double dx = (x - u) / 20.0, dy = (y - v) / 15.0, r = std::sqrt(dx * dx + dy * dy);
        if (r < 0.8)  // well inside: the texture pixel at (x, y) - centre + (w-1)/2, bilinear on a ramp
        {
          const double tx = x - u + 19.5;
          EXPECT_NEAR(img.at<std::uint8_t>(y, x), 40 + 5 * tx, 1.01) << "frame " << k << " (" << x << "," << y << ")";
          EXPECT_EQ(mask.at<std::uint8_t>(y, x), 1);
        }
        else if (r > 1.2)  // well outside: the source untouched
        {
          EXPECT_EQ(img.at<std::uint8_t>(y, x), in.at<std::uint8_t>(y, x));
          EXPECT_EQ(mask.at<std::uint8_t>(y, x), 0);
        }
      }
  }
}

TEST(SimComposite, CommandLineAndBadInputNameTheProblem)
{
  TTempDir src("composite_cli_src"), dst("composite_cli_dst");
  std::ostringstream o0, e0;
  ASSERT_EQ(runRenderApp({scenarioPath("default"), src.path.string(), "--frames", "3"}, o0, e0), 0) << e0.str();
  const std::string texPath = (src.path / "texture.png").string();
  ASSERT_TRUE(cv::imwrite(texPath, cv::Mat(20, 20, CV_8UC3, cv::Scalar(10, 200, 90))));
  const std::string s = src.path.string(), d = dst.path.string();

  std::ostringstream out, err;
  EXPECT_EQ(runCompositeApp({s, d, "--object", texPath, "--crop", "2,2,16,16", "--scale", "1,2", "--path", "0,60,159,60",
                             "--span", "0,2", "--wave", "5,10"},
                            out, err),
            0)
      << err.str();
  EXPECT_NE(out.str().find("wrote 3 frames"), std::string::npos) << out.str();
  EXPECT_EQ(cv::imread((dst.path / "rgb" / "000001.png").string(), cv::IMREAD_UNCHANGED).type(), CV_8UC1);
  // A corrupt source frame is skipped and counted; the others are written.
  {
    std::ofstream bad(src.path / "rgb" / "000001.png", std::ios::trunc);
    bad << "not a png";
  }
  TTempDir dst2("composite_cli_dst2");
  std::ostringstream o1, e1;
  EXPECT_EQ(runCompositeApp({s, dst2.path.string(), "--object", texPath}, o1, e1), 0) << e1.str();
  EXPECT_NE(o1.str().find("wrote 2 frames"), std::string::npos) << o1.str();
  EXPECT_NE(o1.str().find("1 unreadable source frames skipped"), std::string::npos) << o1.str();

  const auto code = [](const std::vector<std::string>& args, std::string& message) { return exitCode(runCompositeApp, args, message); };
  std::string m;
  EXPECT_EQ(code({"--help"}, m), 0);
  EXPECT_EQ(code({s, d}, m), 2);
  EXPECT_NE(m.find("--object"), std::string::npos) << m;
  EXPECT_EQ(code({s, d, "--crop", "1,1,4,4"}, m), 2);
  EXPECT_EQ(code({s, d, "--object", texPath, "--crop", "1,1,4"}, m), 2);
  EXPECT_NE(m.find("--crop"), std::string::npos) << m;
  EXPECT_EQ(code({s, d, "--object", texPath, "--scale", "0"}, m), 2);
  EXPECT_EQ(code({s, d, "--object", texPath, "--span", "5,2"}, m), 2);
  EXPECT_EQ(code({s, d, "--object", texPath, "--wave", "3,0"}, m), 2);
  EXPECT_EQ(code({s, d, "--object", texPath, "--bogus", "1"}, m), 2);
  EXPECT_EQ(code({s, d, "--object", texPath, "--crop", "10,10,16,16"}, m), 1);
  EXPECT_NE(m.find("texture.png"), std::string::npos) << m;
  EXPECT_NE(m.find("not inside"), std::string::npos) << m;
  EXPECT_EQ(code({s, d, "--object", "/nonexistent/hand.png"}, m), 1);
  EXPECT_NE(m.find("/nonexistent/hand.png"), std::string::npos) << m;
  EXPECT_EQ(code({"/nonexistent/folder", d, "--object", texPath}, m), 1);
  EXPECT_NE(m.find("/nonexistent/folder"), std::string::npos) << m;
  EXPECT_EQ(code({s, s, "--object", texPath}, m), 1);
  EXPECT_NE(m.find("is the source folder"), std::string::npos) << m;
}

// ---------------------------------------------------------------------------------------------
// imm-rotate: a rotating camera made from a still camera's video
// ---------------------------------------------------------------------------------------------
namespace
{
/** A still camera's sequence with known truth: a smooth random background with bright dots at known
 * pixels, and a textured 24x24 square that crosses the image at 5 px per frame and stands still for
 * `kPause` frames on the way. */
struct TStillScene
{
  static constexpr int kW = 200, kH = 150, kFrames = 40, kPauseFrom = 15, kPause = 5;
  camera::CPinholeCamera cam{kW, kH, 150, 150, 99.5, 74.5};
  cv::Mat background;
  std::vector<Vec2> dots{{30, 110}, {170, 30}, {160, 120}, {100, 20}, {110, 130}};
  cv::Mat square;

  TStillScene()
  {
    cv::RNG rng(7);
    background.create(kH, kW, CV_8UC1);
    rng.fill(background, cv::RNG::UNIFORM, 40, 160);
    cv::GaussianBlur(background, background, {0, 0}, 2.0);
    for (const Vec2& d : dots)
      for (int y = -4; y <= 4; ++y)
        for (int x = -4; x <= 4; ++x)
        {
          const double g = 90 * std::exp(-(x * x + y * y) / (2 * 1.2 * 1.2));
          auto& px = background.at<std::uint8_t>(static_cast<int>(d.y()) + y, static_cast<int>(d.x()) + x);
          px = cv::saturate_cast<std::uint8_t>(px + g);
        }
    square.create(24, 24, CV_8UC1);
    rng.fill(square, cv::RNG::UNIFORM, 170, 256);  // textured, brighter than the world
  }

  /** Top-left corner of the square in frame i. */
  cv::Point squareAt(int i) const
  {
    const int moved = i < kPauseFrom ? i : std::max(kPauseFrom, i - kPause);
    return {4 + 5 * moved, 40};
  }

  cv::Mat frame(int i) const
  {
    cv::Mat f = background.clone();
    const cv::Point p = squareAt(i);
    const cv::Rect r = cv::Rect(p, square.size()) & cv::Rect(0, 0, kW, kH);
    square(cv::Rect(0, 0, r.width, r.height)).copyTo(f(r));
    return f;
  }

  void write(const fs::path& folder) const
  {
    io::CDatasetWriter w(folder.string(), cam);
    for (int i = 0; i < kFrames; ++i) w.addFrame(i / 30.0, frame(i));
  }
};

/** Sub-pixel centroid of the bright blob within r px of uv (intensity above the local median). */
Vec2 blobCentroid(const cv::Mat& img, const Vec2& uv, int r)
{
  const int u0 = static_cast<int>(std::lround(uv.x())), v0 = static_cast<int>(std::lround(uv.y()));
  std::vector<int> vals;
  for (int y = v0 - r; y <= v0 + r; ++y)
    for (int x = u0 - r; x <= u0 + r; ++x) vals.push_back(img.at<std::uint8_t>(y, x));
  std::nth_element(vals.begin(), vals.begin() + static_cast<long>(vals.size() / 2), vals.end());
  const double base = vals[vals.size() / 2];
  double sw = 0, su = 0, sv = 0;
  for (int y = v0 - r; y <= v0 + r; ++y)
    for (int x = u0 - r; x <= u0 + r; ++x)
    {
      const double w = std::max(0.0, img.at<std::uint8_t>(y, x) - base - 30.0);
      sw += w, su += w * x, sv += w * y;
    }
  return Vec2(su / sw, sv / sw);
}
}  // namespace

TEST(SimRotate, EveryStaticPointIsWhereTheTrueRotationPutsIt)
{
  TTempDir src("rotate_src"), dst("rotate_dst");
  const TStillScene scene;
  scene.write(src.path);
  TRotatedViewOptions o;
  o.panDeg = 4, o.tiltDeg = 3, o.rollDeg = 1.5, o.periodFrames = 30;
  o.width = 160, o.height = 120;
  const TRotatedViewStats st = rotateStillVideo(src.path.string(), dst.path.string(), o);
  EXPECT_EQ(st.frames, static_cast<std::size_t>(TStillScene::kFrames));
  EXPECT_EQ(st.skipped, 0u);
  EXPECT_EQ(st.maxOutsideFraction, 0.0) << "a 160x120 crop of a 200x150 view stays inside for these angles";
  EXPECT_GT(st.maxAngleDeg, 4.0);
  const auto virt = camera::loadCalibFile((dst.path / "calib.txt").string());
  EXPECT_EQ(virt->modelName(), "pinhole");
  EXPECT_EQ(virt->width(), 160);
  EXPECT_DOUBLE_EQ(virt->fx(), 150.0);
  const auto gt = core::readTumTrajectory((dst.path / "groundtruth.txt").string());
  ASSERT_EQ(gt.size(), static_cast<std::size_t>(TStillScene::kFrames));
  const auto labels = dataLines(dst.path / "motion_labels.txt");
  ASSERT_EQ(labels.size(), gt.size());
  EXPECT_NE(labels[0].find("stationary"), std::string::npos);
  EXPECT_NE(labels[5].find("rotation"), std::string::npos);
  const auto rgb = dataLines(dst.path / "rgb.txt");
  // The centroid of a dot on a textured background is itself biased by up to ~0.07 px (measured on
  // the source image), and bilinear resampling blurs it a little: exact geometry shows as < 0.1 px
  // on average; a wrong convention (half a pixel, a transposed rotation) as several pixels.
  double worst = 0, sum = 0;
  int n = 0;
  for (int i = 0; i < TStillScene::kFrames; ++i)
  {
    const auto q = rotatedViewQuaternion(o, static_cast<std::size_t>(i));
    EXPECT_NEAR(gt[i].q_W_C[0], q[0], 1e-12);
    EXPECT_NEAR(gt[i].q_W_C[1], q[1], 1e-12);
    EXPECT_NEAR(gt[i].q_W_C[3], q[3], 1e-12);
    EXPECT_EQ(gt[i].p_W_C.norm(), 0.0) << "a rotation about the optical centre";
    EXPECT_NEAR(gt[i].timestamp, i / 30.0, 1e-6);
    std::istringstream line(rgb[i]);
    double t;
    std::string name;
    line >> t >> name;
    const cv::Mat img = cv::imread((dst.path / name).string(), cv::IMREAD_UNCHANGED);
    ASSERT_EQ(img.type(), CV_8UC1);
    const Mat3 R = math::quatToRotation(gt[i].q_W_C);
    for (const Vec2& d : scene.dots)
    {
      Vec2 uv;
      ASSERT_TRUE(virt->project(R.transpose() * scene.cam.unproject(d).unitVector(), uv));
      if (!virt->isInImage(uv, 8)) continue;
      const double e = (blobCentroid(img, uv, 6) - uv).norm();
      worst = std::max(worst, e);
      sum += e, ++n;
    }
  }
  ASSERT_GT(n, 2 * TStillScene::kFrames) << "dots seen";
  EXPECT_LT(worst, 0.25) << "px between where the true rotation puts a static dot and where it is";
  EXPECT_LT(sum / n, 0.1) << "px on average";
}

TEST(SimRotate, MasksMarkWhatMovesAlsoWhileItStandsStillForAWhile)
{
  TTempDir src("rotate_mask_src"), dst("rotate_mask_dst");
  const TStillScene scene;
  scene.write(src.path);
  TRotatedViewOptions o;
  o.panDeg = o.tiltDeg = o.rollDeg = 0;  // masks in the source's pixels
  o.width = TStillScene::kW, o.height = TStillScene::kH;
  o.dilatePx = 2;
  rotateStillVideo(src.path.string(), dst.path.string(), o);
  // The background model is learned over the whole video before labelling: it is the world, also
  // where the square stands still for kPause frames (a model that kept learning while labelling
  // would take the standing square into the background).
  const cv::Mat bg = cv::imread((dst.path / "background.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(bg.type(), CV_8UC1);
  cv::Mat diff;
  cv::absdiff(bg, scene.background, diff);
  EXPECT_LT(cv::mean(diff)[0], 3.0);
  std::size_t falsePx = 0, truePx = 0, hitPx = 0, bgPx = 0, pausedPx = 0, pausedHitPx = 0;
  for (int i = 0; i < TStillScene::kFrames; ++i)
  {
    char name[32];
    std::snprintf(name, sizeof(name), "%06d.png", i);
    const cv::Mat mask = cv::imread((dst.path / "masks" / name).string(), cv::IMREAD_UNCHANGED);
    ASSERT_EQ(mask.type(), CV_8UC1);
    const cv::Rect sq(scene.squareAt(i), scene.square.size());
    const bool paused = i > TStillScene::kPauseFrom && i <= TStillScene::kPauseFrom + TStillScene::kPause;
    for (int y = 0; y < mask.rows; ++y)
      for (int x = 0; x < mask.cols; ++x)
      {
        const bool inside = sq.contains({x, y});
        const bool near = x >= sq.x - 4 && x < sq.br().x + 4 && y >= sq.y - 4 && y < sq.br().y + 4;
        const bool m = mask.at<std::uint8_t>(y, x) != 0;
        if (inside) ++truePx, hitPx += m ? 1 : 0;
        if (inside && paused) ++pausedPx, pausedHitPx += m ? 1 : 0;
        if (!near) ++bgPx, falsePx += m ? 1 : 0;
      }
  }
  EXPECT_GE(static_cast<double>(hitPx) / truePx, 0.9) << "of the square's pixels marked moving";
  EXPECT_GE(static_cast<double>(pausedHitPx) / pausedPx, 0.9) << "of the square's pixels while it stands still";
  EXPECT_LE(static_cast<double>(falsePx) / bgPx, 0.01) << "of the still background marked moving";
}

TEST(SimRotate, VideoFilesCommandLineAndBadInputNameTheProblem)
{
  TTempDir src("rotate_cli_src"), dst("rotate_cli_dst");
  const TStillScene scene;
  fs::create_directories(src.path);
  const std::string video = (src.path / "still.avi").string();
  {
    cv::VideoWriter w(video, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 25.0, {TStillScene::kW, TStillScene::kH}, true);
    ASSERT_TRUE(w.isOpened());
    for (int i = 0; i < 12; ++i)
    {
      cv::Mat bgr;
      cv::cvtColor(scene.frame(i), bgr, cv::COLOR_GRAY2BGR);
      w.write(bgr);
    }
  }
  const std::string calib = (src.path / "calib.txt").string();
  camera::saveCalibFile(scene.cam, calib);
  const std::string d = dst.path.string();
  std::ostringstream out, err;
  ASSERT_EQ(runRotateApp({video, d, "--calib", calib, "--size", "160,120", "--rotate", "2,1,0.5", "--period", "20"}, out, err), 0)
      << err.str();
  EXPECT_NE(out.str().find("wrote 12 frames"), std::string::npos) << out.str();
  const auto rgb = dataLines(dst.path / "rgb.txt");
  ASSERT_EQ(rgb.size(), 12u);
  EXPECT_NE(rgb[5].find("0.200000"), std::string::npos) << "frame 5 of a 25 Hz video: " << rgb[5];
  EXPECT_EQ(cv::imread((dst.path / "rgb" / "000003.png").string(), cv::IMREAD_UNCHANGED).type(), CV_8UC3)
      << "a colour source gives colour frames";
  EXPECT_TRUE(fs::exists(dst.path / "masks" / "000003.png"));

  const auto code = [](const std::vector<std::string>& args, std::string& message) { return exitCode(runRotateApp, args, message); };
  std::string m;
  EXPECT_EQ(code({"--help"}, m), 0);
  EXPECT_EQ(code({video}, m), 2);
  EXPECT_EQ(code({video, d, "--rotate", "1,2"}, m), 2);
  EXPECT_NE(m.find("--rotate"), std::string::npos) << m;
  EXPECT_EQ(code({video, d, "--size", "10,10"}, m), 2);
  EXPECT_EQ(code({video, d, "--bogus", "1"}, m), 2);
  EXPECT_EQ(code({video, d, "--calib", calib, "--rotate", "90,0,0"}, m), 1);
  EXPECT_NE(m.find("45"), std::string::npos) << m;
  EXPECT_EQ(code({video, d}, m), 1);
  EXPECT_NE(m.find("--calib"), std::string::npos) << m;
  EXPECT_EQ(code({video, d, "--calib", "/nonexistent/calib.txt"}, m), 1);
  EXPECT_NE(m.find("/nonexistent/calib.txt"), std::string::npos) << m;
  EXPECT_EQ(code({video, d, "--calib", calib, "--size", "400,300"}, m), 1);
  EXPECT_NE(m.find("larger than the source"), std::string::npos) << m;
  EXPECT_EQ(code({"/nonexistent/video.mp4", d, "--calib", calib}, m), 1);
  EXPECT_NE(m.find("/nonexistent/video.mp4"), std::string::npos) << m;
  const std::string notVideo = (src.path / "notes.txt").string();
  std::ofstream(notVideo) << "not a video\n";
  EXPECT_EQ(code({notVideo, d, "--calib", calib}, m), 1);
  EXPECT_NE(m.find("notes.txt"), std::string::npos) << m;
  // A dataset folder as its own output would be overwritten.
  EXPECT_EQ(code({d, d}, m), 1);
  EXPECT_NE(m.find("is the source folder"), std::string::npos) << m;
}

TEST(SimComposite, VideoObjectIsPastedWhereItsMasksAreUntilItsVideoEnds)
{
  // A still camera's video (TStillScene: a textured square moving over a textured world) through
  // imm-rotate at rest gives the masks; its moving square is pasted into a rendered sequence.
  TTempDir still("composite_video_still"), obj("composite_video_obj"), src("composite_video_src"), dst("composite_video_dst");
  const TStillScene scene;
  scene.write(still.path);
  TRotatedViewOptions ro;
  ro.panDeg = ro.tiltDeg = ro.rollDeg = 0;
  ro.width = TStillScene::kW, ro.height = TStillScene::kH;
  ro.dilatePx = 0;
  rotateStillVideo(still.path.string(), obj.path.string(), ro);
  std::ostringstream out, err;
  ASSERT_EQ(runRenderApp({scenarioPath("default"), src.path.string(), "--frames", "50", "--set", "render.noise_sigma_grey=0"}, out, err), 0)
      << err.str();
  TCompositeObject o;
  o.video = obj.path.string();
  o.videoStart = 5;
  o.firstFrame = 10;
  const TCompositeStats st = compositeMovingObjects(src.path.string(), dst.path.string(), {o});
  EXPECT_EQ(st.frames, 50u);
  // Video frames 5..39 go to output frames 10..44; then the video has ended.
  EXPECT_EQ(st.objectFrames, 35u);
  const auto cam = camera::loadCalibFile((src.path / "calib.txt").string());
  // The video frame's centre sits at the image centre, scale 1: output (x, y) shows video pixel
  // (x, y) - c_out + c_video.
  const double du = 0.5 * (TStillScene::kW - 1) - 0.5 * (cam->width() - 1), dv = 0.5 * (TStillScene::kH - 1) - 0.5 * (cam->height() - 1);
  for (int i : {10, 20, 44, 45})
  {
    char name[32];
    std::snprintf(name, sizeof(name), "%06d.png", i);
    const cv::Mat img = cv::imread((dst.path / "rgb" / name).string(), cv::IMREAD_GRAYSCALE);
    const cv::Mat mask = cv::imread((dst.path / "masks" / name).string(), cv::IMREAD_UNCHANGED);
    if (i == 45)
    {
      EXPECT_EQ(cv::countNonZero(mask), 0) << "the video has ended";
      continue;
    }
    const cv::Mat videoFrame = scene.frame(5 + (i - 10));
    const cv::Rect sq(scene.squareAt(5 + (i - 10)), scene.square.size());
    int inside = 0, outsideMarked = 0;
    for (int y = 0; y < img.rows; ++y)
      for (int x = 0; x < img.cols; ++x)
      {
        const int vx = static_cast<int>(std::lround(x + du)), vy = static_cast<int>(std::lround(y + dv));
        const bool inner = vx >= sq.x + 2 && vx < sq.br().x - 2 && vy >= sq.y + 2 && vy < sq.br().y - 2;
        const bool near = vx >= sq.x - 12 && vx < sq.br().x + 12 && vy >= sq.y - 12 && vy < sq.br().y + 12;
        if (inner && vx >= 0 && vy >= 0 && vx < TStillScene::kW && vy < TStillScene::kH)
        {
          ++inside;
          EXPECT_EQ(mask.at<std::uint8_t>(y, x), 1);
          EXPECT_NEAR(img.at<std::uint8_t>(y, x), videoFrame.at<std::uint8_t>(vy, vx), 2) << "frame " << i;
        }
        else if (!near)
          outsideMarked += mask.at<std::uint8_t>(y, x) != 0;
      }
    EXPECT_GT(inside, 100) << "frame " << i;
    EXPECT_EQ(outsideMarked, 0) << "frame " << i;
  }
  // A video object needs masks/; the command line names the option and the folder.
  TTempDir bare("composite_video_bare");
  scene.write(bare.path);
  std::ostringstream o2, e2;
  EXPECT_EQ(runCompositeApp({src.path.string(), dst.path.string() + "2", "--object-video", bare.path.string()}, o2, e2), 1);
  EXPECT_NE(e2.str().find("masks"), std::string::npos) << e2.str();
  std::ostringstream o3, e3;
  EXPECT_EQ(runCompositeApp({src.path.string(), dst.path.string() + "3", "--object", "x.png", "--video-start", "3"}, o3, e3), 2);
  EXPECT_NE(e3.str().find("--object-video"), std::string::npos) << e3.str();
  fs::remove_all(dst.path.string() + "2");
  fs::remove_all(dst.path.string() + "3");
}
