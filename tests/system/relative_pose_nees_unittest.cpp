/* Consistency of the relative motion given to the shadow filter's tests (issue 27; doc/shadow.md, "The
 * three-ray test on relative motion"): the SLAM's frame-to-frame increments, each with the covariance
 * Cov([v; w]) dt^2 of the fused velocity estimate, composed over a window of frames exactly as for a
 * shadow feature (TRayTrack::advance), against the renderer's ground truth. NEES of the relative rotation
 * (3 dof, free of the monocular scale) and of the relative pose (6 dof, the ground-truth translation in the
 * run's units through the scale of its Sim(3) alignment), over windows starting every 5 frames. */
#include <gtest/gtest.h>
#include <immslam/eval/ate.h>
#include <immslam/eval/consistency.h>
#include <immslam/math/chi2.h>
#include <immslam/shadow/CRayClassifier.h>
#include <immslam/shadow/relative_pose.h>
#include <immslam/shadow/shadow_types.h>
#include <immslam/sim/CSyntheticSource.h>
#include <immslam/system/CMonoSlamSystem.h>
#include <mrpt/config/CConfigFile.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "test_helpers.h"

namespace immslam::test
{
namespace
{
/** One run of the full system (ini/imm7-shadow.ini) on a rendered scenario: per frame the pose, the
 * increment's covariance as the system gives it to the shadow filter, and the ground truth. */
struct TRun
{
  std::vector<Vec3> r;
  std::vector<Vec4> q;
  std::vector<Mat6> cov;
  std::vector<double> dt;
  std::vector<sim::EMotionLabel> label;  ///< the renderer's motion label of each frame
  core::TTrajectory gt;
  double scale = 1;  ///< of the Sim(3) alignment: gt = s R est + t
  double atePercentOfPath = 0;
};

TRun runSystem(const std::string& scenario, int seed, const std::vector<std::string>& overrides = {})
{
  std::vector<std::string> o = overrides;
  o.push_back("scenario.seed=" + std::to_string(seed));
  sim::CSyntheticSource src(sourceDir() + "/ini/scenarios/" + scenario, o);
  mrpt::config::CConfigFile cfg(sourceDir() + "/ini/imm7-shadow.ini");
  system::CMonoSlamSystem sys(cfg, src.calibration());
  TRun run;
  core::TTrajectory est;
  io::TFrame fr;
  std::string why;
  while (src.next(fr, why) == io::ENextStatus::Frame)
  {
    const auto& f = sys.processFrame(fr.timestamp, fr.grey);
    const double dt = f.slam->dtFrames;
    run.r.push_back(sys.slam().cameraPosition());
    run.q.push_back(sys.slam().cameraOrientation());
    run.cov.push_back(sys.slam().velocityCovariance() * dt * dt);  // CMonoSlamSystem::cameraMotion
    run.dt.push_back(dt);
    run.label.push_back(src.label(run.label.size()));
    est.push_back({fr.timestamp, run.r.back(), run.q.back()});
  }
  run.gt = *src.groundTruth();
  const auto ate = eval::computeAte(est, run.gt, eval::EAlignment::Sim3);
  run.scale = ate.scale;
  run.atePercentOfPath = 100 * ate.rmseOverPath;
  return run;
}

struct TNees
{
  std::vector<double> rotation, pose, poseLocalScale;
};

/** Which windows addNees() takes, by the renderer's motion labels over the window. */
enum class EWindows
{
  All,
  Translating,     ///< every frame's label General
  NotTranslating,  ///< no frame's label General (still or rotating)
};

/** NEES of the relative motion over `window` frames, windows starting every 5 frames from frame `from`. */
void addNees(const TRun& run, int window, std::size_t from, TNees& out, EWindows which = EWindows::All)
{
  const std::size_t w = static_cast<std::size_t>(window);
  for (std::size_t a = from; a + w < run.r.size() && a + w < run.gt.size(); a += 5)
  {
    const auto first = run.label.begin() + static_cast<std::ptrdiff_t>(a + 1);
    const auto last = run.label.begin() + static_cast<std::ptrdiff_t>(a + w + 1);
    const auto nGeneral = std::count(first, last, sim::EMotionLabel::General);
    if (which == EWindows::Translating && nGeneral != static_cast<std::ptrdiff_t>(w)) continue;
    if (which == EWindows::NotTranslating && nGeneral != 0) continue;
    shadow::TRayTrack track;
    track.start(0, Vec2::Zero());
    for (std::size_t k = a + 1; k <= a + w; ++k)
    {
      const auto m = shadow::TCameraMotion::FromPoses(run.r[k - 1], run.q[k - 1], run.r[k], run.q[k]);
      track.advance(static_cast<std::int64_t>(k), run.dt[k], m.t, m.dq, run.cov[k]);
    }
    const auto g = shadow::TCameraMotion::FromPoses(run.gt[a].p_W_C, run.gt[a].q_W_C, run.gt[a + w].p_W_C,
                                                    run.gt[a + w].q_W_C);
    const Vec6 d = shadow::posePerturbation(track.T_0k.t, track.T_0k.q, g.t / run.scale, g.dq);
    const Mat6& P = track.T_0k.cov;
    out.rotation.push_back(eval::nees(d.tail<3>(), P.bottomRightCorner<3, 3>()));
    out.pose.push_back(eval::nees(d, P));
    // The window's own scale (the tests' rays meet or not whatever the scale of the relative motion):
    // d(s) = d0 + s e with e = [g.t / scale; 0], the NEES minimised over s (5 dof).
    Vec6 e = Vec6::Zero();
    e.head<3>() = g.t / run.scale;
    const Vec6 d0 = d - e;
    const Vec6 We = P.ldlt().solve(e);
    const double s = e.dot(We) > 0 ? -d0.dot(We) / e.dot(We) : 1.0;
    out.poseLocalScale.push_back(eval::nees(d0 + s * e, P));
  }
}

struct TSummary
{
  double median = 0, inside95 = 0;  ///< median NEES, fraction below the chi-square 95 % quantile
};

TSummary summarise(std::vector<double> v, double chi95)
{
  TSummary s;
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  s.median = v[v.size() / 2];
  s.inside95 = static_cast<double>(std::count_if(v.begin(), v.end(), [&](double x) { return x < chi95; })) /
               static_cast<double>(v.size());
  return s;
}

/** The chi-square 95 % bound of NEES with this many degrees of freedom. */
double bound95(int dof) { return math::chi2Quantile(0.95, dof); }

void report(const char* what, int window, const TNees& n)
{
  const TSummary r = summarise(n.rotation, bound95(3)), p = summarise(n.pose, bound95(6)),
                 l = summarise(n.poseLocalScale, bound95(5));
  std::printf("%s, %2d frames: %zu windows; NEES median / inside 95 %%: rotation %.2f / %.1f %% (chi2_3 median "
              "2.37), pose %.2f / %.1f %% (chi2_6: 5.35), pose at the window's scale %.2f / %.1f %% (chi2_5: 4.35)\n",
              what, window, n.rotation.size(), r.median, 100 * r.inside95, p.median, 100 * p.inside95, l.median,
              100 * l.inside95);
}
}  // namespace

TEST(RelativePoseNees, ComposedIncrementsAreNotOverConfidentInAStaticWorld)
{
  // Rendered hand-held paths of a static room (ini/scenarios/handheld.ini, seeds 1-3, 300 frames each),
  // windows from frame 1 (the start at rest included). Measured, NEES median / inside the 95 % bound,
  // rotation (3 dof) and pose (6 dof): 5 frames 0.36 / 93.2 %, 0.69 / 89.8 %; 10 frames 0.53 / 94.3 %,
  // 0.90 / 93.1 %; 20 frames 0.49 / 98.2 %, 1.04 / 97.0 %; 40 frames 0.33 / 97.4 %, 0.74 / 96.8 %.
  // The bulk is conservative (medians below the chi-square medians 2.37 and 5.35: the velocity's
  // covariance dt^2 per frame overstates the increments' error); the windows outside the bound are
  // mostly where the camera starts moving while the bank still says stationary. A covariance 10 x too
  // small would put the rotation median at about 3.6.
  std::vector<TRun> runs;
  for (int seed = 1; seed <= 3; ++seed) runs.push_back(runSystem("handheld.ini", seed));
  for (int window : {5, 10, 20, 40})
  {
    TNees n;
    for (const auto& run : runs) addNees(run, window, 1, n);
    report("handheld.ini seeds 1-3", window, n);
    const TSummary r = summarise(n.rotation, bound95(3)), p = summarise(n.pose, bound95(6));
    EXPECT_LT(r.median, math::chi2Quantile(0.5, 3)) << "window " << window;
    EXPECT_LT(p.median, math::chi2Quantile(0.5, 6)) << "window " << window;
    EXPECT_GE(r.inside95, 0.90) << "window " << window;
    EXPECT_GE(p.inside95, 0.85) << "window " << window;
  }
}

// Reported only, not a test (the hold-out family of doc/shadow.md, seeds 101-110, without and with its
// moving objects; windows split by the renderer's motion labels): run with
//   build/tests/system_unittest --gtest_filter='RelativePoseNees.*' --gtest_also_run_disabled_tests
TEST(RelativePoseNees, DISABLED_HoldoutReport)
{
  for (const bool objects : {false, true})
  {
    std::vector<TRun> runs;
    for (int seed = 101; seed <= 110; ++seed)
      runs.push_back(runSystem("holdout/pause-pan-movers.ini", seed,
                               {std::string("objects.enabled=") + (objects ? "true" : "false")}));
    for (int window : {5, 10, 20, 40})
    {
      TNees moving, still;
      for (const auto& run : runs)
      {
        addNees(run, window, 1, moving, EWindows::Translating);
        addNees(run, window, 1, still, EWindows::NotTranslating);
      }
      report("  translating throughout", window, moving);
      report("  not translating throughout", window, still);
      TNees all;
      for (std::size_t i = 0; i < runs.size(); ++i)
      {
        TNees n;
        addNees(runs[i], window, 1, n);
        if (window == 20)
          std::printf("  seed %zu: ATE %.2f %% of path, rotation NEES inside 95 %% %.1f %%\n", 101 + i,
                      runs[i].atePercentOfPath, 100 * summarise(n.rotation, bound95(3)).inside95);
        all.rotation.insert(all.rotation.end(), n.rotation.begin(), n.rotation.end());
        all.pose.insert(all.pose.end(), n.pose.begin(), n.pose.end());
        all.poseLocalScale.insert(all.poseLocalScale.end(), n.poseLocalScale.begin(), n.poseLocalScale.end());
      }
      report(objects ? "pause-pan-movers 101-110, with objects" : "pause-pan-movers 101-110, static world", window, all);
    }
  }
}
}  // namespace immslam::test
