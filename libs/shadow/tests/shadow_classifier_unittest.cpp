/* Tests: the static/dynamic classifier (Sec. III-A) on measurement-level simulations of a hand-held
 * camera (0.2-0.5 units/s, 30 Hz, f = 200 px, 1 px noise, camera motion given as noisy increments
 * with their covariance): static points must rarely be called dynamic (<= alpha = 5 %), moving
 * points almost never static (<= 1 %); and the single three-ray test alone is calibrated (chi-square
 * statistic, rejection rate alpha) on independent trials with correlated relative poses. */
#include <gtest/gtest.h>
#include <immslam/eval/classification.h>
#include <immslam/shadow/CRayClassifier.h>
#include <immslam/shadow/CShadowFilter.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "shadow_test_utils.h"

using namespace immslam;
using namespace immslam::shadow;
using namespace immslam::shadow::test;

namespace
{
/** How a simulated moving point moves. */
enum class EMotionKind
{
  Static,
  Random3D,      ///< constant velocity in a uniformly random direction
  AlongRay,      ///< along its first viewing ray (towards or away from the camera)
  AcrossRay      ///< perpendicular to its first viewing ray
};

struct TSimPoint
{
  EMotionKind kind = EMotionKind::Static;
  Vec3 p0 = Vec3::Zero();
  Vec3 vel = Vec3::Zero();  ///< length per frame
  std::int64_t id = -1;
  EShadowClass decided = EShadowClass::Pending;
  int decisionAge = 0;
  double promotedRhoError = 0, promotedRhoSigma = 0;
  bool promoted = false;
  int evaluations = 0, rejections = 0;  ///< of the classifier's per-frame tests
  double speedPxAtDecision = 0;         ///< |vel| f / distance at the decision (px/frame)
};

struct TClassifierStats
{
  eval::TConfusionMatrix cm;
  std::map<EMotionKind, std::array<int, 3>> byKind;  ///< [pending, static, dynamic]
  double sumAgeStatic = 0, sumAgeDynamic = 0;
  int nStaticOk = 0, nDynamicOk = 0;
  double sumSpeed = 0;
  int nSpeed = 0;
  double rhoNeesSum = 0;
  int nRho = 0, rhoInside3 = 0;
  double timeMs = 0;
  int frames = 0;
  long staticEvaluations = 0, staticRejections = 0;
  int guaranteedMoving = 0, guaranteedStatic = 0;  ///< movers faster than the power guarantee
};

constexpr double kFps = 30;

void runSequence(Rng& rng, const CShadowFilter::TOptions& opts, int nStatic, int nMoving, int nFrames,
                 double sigmaT, double sigmaTheta, TClassifierStats& st)
{
  const double guaranteedPx = opts.static_min_velocity_px;
  const auto cam = simCamera();
  CShadowFilter filter(opts, cam);
  const double speed = uniform(rng, 0.2, 0.5) / kFps;
  THandheldPath path = randomHandheldPath(rng, speed);
  std::vector<TPose> poses(nFrames);
  for (int k = 0; k < nFrames; ++k)
  {
    poses[k].r = path.position(k);
    poses[k].q = path.orientation(k);
    if (k > 0)
    {
      st.sumSpeed += (poses[k].r - poses[k - 1].r).norm() * kFps;
      ++st.nSpeed;
    }
  }
  // Points seen at frame 0, at depths 1-5, away from the border.
  std::vector<TSimPoint> pts;
  for (int i = 0; i < nStatic + nMoving; ++i)
  {
    TSimPoint p;
    const Vec2 uv(uniform(rng, 40, cam->width() - 40), uniform(rng, 30, cam->height() - 30));
    const Vec3 ray = cam->unproject(uv).unitVector();
    const double depth = uniform(rng, 1, 5);
    p.p0 = poses[0].r + poses[0].R() * (ray * depth / ray.z());
    if (i >= nStatic)
    {
      const double v = uniform(rng, 0.05, 1.0) / kFps;
      const int kind = i % 3;
      const Vec3 rayW = poses[0].R() * ray;
      if (kind == 0)
      {
        p.kind = EMotionKind::Random3D;
        p.vel = v * randomUnit(rng);
      }
      else if (kind == 1)
      {
        p.kind = EMotionKind::AlongRay;
        p.vel = (uniform(rng, 0, 1) < 0.5 ? -v : v) * rayW;
      }
      else
      {
        p.kind = EMotionKind::AcrossRay;
        p.vel = v * randomUnit(rng).cross(rayW).normalized();
      }
    }
    pts.push_back(p);
  }
  Mat6 Cinc = Mat6::Zero();
  Cinc.topLeftCorner<3, 3>() = sigmaT * sigmaT * Mat3::Identity();
  Cinc.bottomRightCorner<3, 3>() = sigmaTheta * sigmaTheta * Mat3::Identity();
  std::map<std::int64_t, size_t> byId;
  for (int k = 0; k < nFrames; ++k)
  {
    TCameraMotion m = pathMotion(poses, k, kFps, Mat6::Zero());
    if (k > 0)
    {
      TUncertainPose inc;
      inc.t = m.t;
      inc.q = m.dq;
      const TUncertainPose noisy = perturbPose(inc, sampleGaussian<6>(rng, Cinc));
      m.t = noisy.t;
      m.dq = noisy.q;
      m.cov_increment = Cinc;
    }
    std::vector<std::pair<std::int64_t, Vec2>> z;
    std::vector<Vec2> newUv;
    for (auto& p : pts)
    {
      const Vec3 pW = p.p0 + p.vel * k;
      const Vec3 pC = poses[k].toCamera(pW);
      Vec2 uv;
      if (!cam->project(pC, uv)) continue;
      uv += opts.sigma_pixel * Vec2(gauss(rng), gauss(rng));
      if (!cam->isInImage(uv, 2)) continue;
      if (k == 0)
        newUv.push_back(uv);
      else if (p.id >= 0)
        z.emplace_back(p.id, uv);
    }
    for (auto& p : pts)
      if (const TShadowFeature* f = p.id >= 0 ? filter.feature(p.id) : nullptr)
      {
        p.evaluations = f->track.evaluations;
        p.rejections = f->track.rejections;
      }
    const TShadowReport& rep = filter.processMeasurements(m, z);
    st.timeMs += rep.timeMs;
    ++st.frames;
    for (const auto& d : rep.decisions)
    {
      TSimPoint& p = pts[byId.at(d.id)];
      p.decided = d.cls;
      p.decisionAge = d.ageFrames;
      p.speedPxAtDecision = p.vel.norm() * cam->fx() / (p.p0 + p.vel * k - poses[k].r).norm();
    }
    for (const auto& pr : rep.promotions)
    {
      TSimPoint& p = pts[byId.at(pr.id)];
      const Vec3 pC = poses[k].toCamera(p.p0 + p.vel * k);
      p.promoted = true;
      p.promotedRhoError = pr.rho - 1.0 / pC.norm();
      p.promotedRhoSigma = pr.sigmaRho;
    }
    if (k == 0)
    {
      const auto ids = filter.addFeatures(newUv);
      for (size_t i = 0; i < ids.size(); ++i)
      {
        pts[i].id = ids[i];
        byId[ids[i]] = i;
      }
    }
  }
  for (const auto& p : pts)
  {
    if (p.id < 0) continue;
    // Movers at least 25 % faster than the guaranteed speed when decided (or never decided: then
    // counted as not static).
    if (p.kind != EMotionKind::Static && (p.decided == EShadowClass::Pending || p.speedPxAtDecision >= 1.25 * guaranteedPx))
    {
      ++st.guaranteedMoving;
      st.guaranteedStatic += p.decided == EShadowClass::Static;
    }
    if (p.kind == EMotionKind::Static)
    {
      st.staticEvaluations += p.evaluations;
      st.staticRejections += p.rejections;
    }
    const int cls = p.decided == EShadowClass::Pending ? 0 : p.decided == EShadowClass::Static ? 1 : 2;
    st.byKind[p.kind][cls]++;
    const eval::EMotionClass truth = p.kind == EMotionKind::Static ? eval::EMotionClass::Static : eval::EMotionClass::Dynamic;
    if (p.decided != EShadowClass::Pending)
      st.cm.add(truth, p.decided == EShadowClass::Static ? eval::EMotionClass::Static : eval::EMotionClass::Dynamic);
    if (p.kind == EMotionKind::Static && p.decided == EShadowClass::Static)
    {
      st.sumAgeStatic += p.decisionAge;
      ++st.nStaticOk;
    }
    if (p.kind != EMotionKind::Static && p.decided == EShadowClass::Dynamic)
    {
      st.sumAgeDynamic += p.decisionAge;
      ++st.nDynamicOk;
    }
    if (p.promoted && p.kind == EMotionKind::Static && p.promotedRhoSigma > 0)
    {
      const double r = p.promotedRhoError / p.promotedRhoSigma;
      st.rhoNeesSum += r * r;
      st.rhoInside3 += std::abs(r) <= 3;
      ++st.nRho;
    }
  }
}

const char* kindName(EMotionKind k)
{
  switch (k)
  {
    case EMotionKind::Static: return "static";
    case EMotionKind::Random3D: return "moving, random direction";
    case EMotionKind::AlongRay: return "moving, along the viewing ray";
    case EMotionKind::AcrossRay: return "moving, across the viewing ray";
  }
  return "?";
}

TClassifierStats runClassifierExperiment(const CShadowFilter::TOptions& opts, int nSequences, unsigned seed,
                                         double sigmaT, double sigmaTheta)
{
  Rng rng(seed);
  TClassifierStats st;
  for (int s = 0; s < nSequences; ++s) runSequence(rng, opts, 20, 20, opts.max_pending_frames + 10, sigmaT, sigmaTheta, st);
  std::printf("[ shadow   ] camera speed %.3f units/s on average; increments sigma_t %.4f, sigma_theta %.4f rad\n",
              st.sumSpeed / st.nSpeed, sigmaT, sigmaTheta);
  for (const auto& [kind, c] : st.byKind)
  {
    const int n = c[0] + c[1] + c[2];
    std::printf("[ shadow   ] %-32s n=%4d  static %5.1f %%  dynamic %5.1f %%  undecided %5.1f %%\n", kindName(kind), n,
                100.0 * c[1] / n, 100.0 * c[2] / n, 100.0 * c[0] / n);
  }
  std::printf("[ shadow   ] mean time to decision: static points -> static %.1f frames (%.2f s), moving -> dynamic %.1f frames (%.2f s)\n",
              st.sumAgeStatic / std::max(1, st.nStaticOk), st.sumAgeStatic / std::max(1, st.nStaticOk) / kFps,
              st.sumAgeDynamic / std::max(1, st.nDynamicOk), st.sumAgeDynamic / std::max(1, st.nDynamicOk) / kFps);
  std::printf("[ shadow   ] promoted rho: normalized error^2 mean %.2f (ideal 1), inside 3 sigma %.1f %% (n=%d)\n",
              st.rhoNeesSum / std::max(1, st.nRho), 100.0 * st.rhoInside3 / std::max(1, st.nRho), st.nRho);
  std::printf("[ shadow   ] single tests of static points rejected: %.2f %% of %ld (alpha = %.2f %%)\n",
              100.0 * st.staticRejections / std::max(1L, st.staticEvaluations), st.staticEvaluations, 100 * opts.alpha);
  std::printf("[ shadow   ] moving points faster than 1.25 x static_min_velocity_px when decided: %d, classified static %d\n",
              st.guaranteedMoving, st.guaranteedStatic);
  std::printf("[ shadow   ] mean time per frame (40 features at start): %.3f ms\n", st.timeMs / st.frames);
  std::cout << st.cm;
  return st;
}

double rate(const std::array<int, 3>& c, int which) { return double(c[which]) / (c[0] + c[1] + c[2]); }
}  // namespace

TEST(ShadowClassifier, HandheldStaticVsMoving)
{
  CShadowFilter::TOptions opts;  // defaults, but for the papers' independent random points:
  opts.decide_lone_dynamic = true;  // each moves alone, no neighbour moves with it
  const TClassifierStats st = runClassifierExperiment(opts, 60, 41, 0.001, 0.0005);
  auto byKind = st.byKind;
  std::array<int, 3> visible{0, 0, 0}, moving{0, 0, 0};
  for (auto k : {EMotionKind::Random3D, EMotionKind::AcrossRay})
    for (int i = 0; i < 3; ++i) visible[i] += byKind[k][i];
  for (auto k : {EMotionKind::Random3D, EMotionKind::AlongRay, EMotionKind::AcrossRay})
    for (int i = 0; i < 3; ++i) moving[i] += byKind[k][i];
  const auto& stat = byKind[EMotionKind::Static];
  std::printf("[ shadow   ] all moving points: static %.2f %%, dynamic %.2f %% (n=%d)\n", 100 * rate(moving, 1),
              100 * rate(moving, 2), moving[0] + moving[1] + moving[2]);
  ASSERT_GE(stat[0] + stat[1] + stat[2], 1000);
  ASSERT_GE(moving[0] + moving[1] + moving[2], 1000);
  // Limits at ~1.2x the measured figures of this deterministic run (seed 41, 60 sequences; measured
  // 2026-11-27), so that a 20 % loss fails.
  EXPECT_LE(rate(stat, 2), 0.017);     // static called dynamic: measured 1.4 % (target: <= alpha)
  // Single tests of static points are calibrated: the relative-motion covariance is right. Measured
  // 4.19 % of 117 725 tests; 2.64 % with the relative-pose cross-covariance dropped from the ray test
  // (tests/mutation/ray-test-cross-covariance-dropped.patch). Both sides: an over-cautious test
  // (inflated covariance) fails as well as an over-confident one.
  const double single = double(st.staticRejections) / st.staticEvaluations;
  EXPECT_GT(single, 0.035);
  EXPECT_LT(single, 0.050);
  EXPECT_LE(rate(visible, 1), 0.005);  // moving in random / across-ray directions called static: 3 of 840
  EXPECT_LE(double(st.guaranteedStatic) / st.guaranteedMoving, 0.01);  // the power guarantee: 0 of 547
  EXPECT_LE(rate(byKind[EMotionKind::AlongRay], 1), 0.127);  // along the ray: 10.6 %, below the guarantee, see README
  EXPECT_GE(rate(visible, 2), 0.97);   // measured 97.5 %
  EXPECT_GE(rate(stat, 1), 0.45);      // static points promoted within max_pending_frames: 53.9 %
  // Promoted inverse distances are consistent: the mean normalized squared error of n chi-square(1)
  // values within 3 sigmas (sqrt(2 / n)) of 1, from both sides (measured 0.93, n = 647).
  EXPECT_NEAR(st.rhoNeesSum / st.nRho, 1.0, 3 * std::sqrt(2.0 / st.nRho));
  EXPECT_GE(double(st.rhoInside3) / st.nRho, 0.97);
}

namespace
{
/** One frame of a sideways drift with some wobble (0.002 units, 0.003 rad): the true camera moves by
 * the increment, the track is advanced by the increment perturbed with covariance `actual` and told
 * `stated`. */
void advanceWithNoisyIncrement(Rng& rng, const Vec3& drift, const Mat6& actual, const Mat6& stated, int frame,
                               TUncertainPose& truth, TRayTrack& track)
{
  TUncertainPose inc;
  inc.t = drift + 0.002 * gauss3(rng);
  inc.q = math::quatFromRotationVector(0.003 * gauss3(rng));
  truth = composePoses(truth, inc);
  const TUncertainPose noisy = perturbPose(inc, sampleGaussian<6>(rng, actual));
  track.advance(frame, 1, noisy.t, noisy.q, stated);
}
}  // namespace

TEST(ShadowClassifier, SingleRayTestIsCalibratedWithCorrelatedPoses)
{
  // The three-ray test of CRayClassifier alone, on independent Monte Carlo trials of a static point
  // seen at frames 0, 10 and 20 by a camera whose relative poses T_0m, T_0k are composed from noisy
  // increments (the chain to k contains the chain to m: their errors are correlated). The pose noise
  // (1.5e-3 units, 1e-3 rad per frame) is about as large in the image as the 1 px pixel noise, so the
  // joint covariance, cross-covariance Cov(delta_k, delta_m) included, decides the statistic: with the
  // right one T is chi-square(3), mean 3, and rejects at alpha = 5 %. Measured (seed 97, 10 000
  // trials): rejection rate 4.67 %, mean T 3.002; with the cross-covariance block dropped
  // (tests/mutation/ray-test-cross-covariance-dropped.patch) 2.86 % and 2.58: both fail.
  // Bands: the rate within 3 binomial sigmas of alpha (+-0.65 %), the mean within 3 sigmas of the
  // mean of 10 000 chi-square(3) values (sqrt(6 / 10 000) = 0.024: +-0.075).
  const auto cam = simCamera();
  TRayClassifierParams params;
  const CRayClassifier cls(params, cam);
  Rng rng(97);
  const double sigmaT = 0.0015, sigmaTheta = 0.001;
  Mat6 Cinc = Mat6::Zero();
  Cinc.topLeftCorner<3, 3>() = sigmaT * sigmaT * Mat3::Identity();
  Cinc.bottomRightCorner<3, 3>() = sigmaTheta * sigmaTheta * Mat3::Identity();
  const int trials = 10000, frames = 20;
  int evaluated = 0, rejected = 0;
  double sumT = 0;
  for (int trial = 0; trial < trials; ++trial)
  {
    // A static point at depth 2-4 in C0, away from the image border.
    const Vec2 uv0(uniform(rng, 60, cam->width() - 60), uniform(rng, 50, cam->height() - 50));
    const Vec3 ray = cam->unproject(uv0).unitVector();
    const Vec3 X = ray * uniform(rng, 2, 4) / ray.z();
    // A sideways drift with some wobble (0.01 units and ~0.2 deg per frame).
    const Vec3 drift(uniform(rng, -1, 1) > 0 ? 0.01 : -0.01, uniform(rng, -0.004, 0.004), uniform(rng, -0.004, 0.004));
    TUncertainPose truth;  // T_0j, true
    TRayTrack track;
    const auto measure = [&](const TUncertainPose& T) {
      Vec2 uv;
      EXPECT_TRUE(cam->project(T.rotation().transpose() * (X - T.t), uv));
      return Vec2(uv + params.sigmaPx * Vec2(gauss(rng), gauss(rng)));
    };
    track.start(0, measure(truth));
    for (int k = 1; k <= frames; ++k)
    {
      advanceWithNoisyIncrement(rng, drift, Cinc, Cinc, k, truth, track);
      if (k == frames / 2 || k == frames) track.addView(measure(truth));
    }
    const TRayTestResult r = cls.test(track);
    if (!r.evaluated) continue;
    ++evaluated;
    rejected += r.test.test.rejected();
    sumT += r.test.test.T;
  }
  const double rate = double(rejected) / evaluated, meanT = sumT / evaluated;
  std::printf("[ shadow   ] three-ray test, correlated relative poses: %d of %d trials evaluated, rejected %.2f %%, "
              "mean T %.3f (chi-square(3): 3)\n",
              evaluated, trials, 100 * rate, meanT);
  ASSERT_GE(evaluated, trials - 10);
  const double sigmaRate = std::sqrt(params.alpha * (1 - params.alpha) / evaluated);
  EXPECT_NEAR(rate, params.alpha, 3 * sigmaRate);
  EXPECT_NEAR(meanT, 3.0, 3 * std::sqrt(6.0 / evaluated));
}

namespace
{
/** Rejection rates of the three-ray test of one point seen at frames 0, 10 and 20, alone and against
 * the map (CRayClassifier::mapScale over 8 static map points measured in the same frames), when the
 * relative poses' true error is `actualScale` times the stated one. `pixelSpeed`: the point moves
 * across its first viewing ray at this many pixels per frame (0: static). */
std::pair<double, double> rejectionRates(double actualScale, double pixelSpeed, int trials, unsigned seed)
{
  const auto cam = simCamera();
  TRayClassifierParams params;
  const CRayClassifier cls(params, cam);
  Rng rng(seed);
  Mat6 Cinc = Mat6::Zero();
  Cinc.topLeftCorner<3, 3>() = 0.0015 * 0.0015 * Mat3::Identity();
  Cinc.bottomRightCorner<3, 3>() = 0.001 * 0.001 * Mat3::Identity();
  const Mat6 Cactual = actualScale * actualScale * Cinc;
  constexpr int kMap = 8, kFrames = 20;
  int evaluated = 0, alone = 0, withMap = 0;
  for (int trial = 0; trial < trials; ++trial)
  {
    // The tested point (index 0) and the map's points, static at depths 2-4 in C0.
    std::vector<Vec3> X;
    for (int i = 0; i <= kMap; ++i)
    {
      const Vec3 ray = cam->unproject(Vec2(uniform(rng, 40, 280), uniform(rng, 30, 210))).unitVector();
      X.push_back(ray * uniform(rng, 2, 4) / ray.z());
    }
    const double depth = X[0].z();
    const Vec3 across = X[0].normalized().cross(randomUnit(rng)).normalized();
    const Vec3 drift(uniform(rng, -1, 1) > 0 ? 0.01 : -0.01, uniform(rng, -0.004, 0.004), uniform(rng, -0.004, 0.004));
    TUncertainPose truth;
    TRayTrack track;
    CMapViews map;
    const auto observe = [&](int k) {
      std::vector<std::pair<std::int64_t, Vec2>> z;
      Vec2 uv0;
      for (int i = 0; i <= kMap; ++i)
      {
        const Vec3 p = i == 0 ? Vec3(X[0] + across * pixelSpeed * k * depth / 200.0) : X[static_cast<std::size_t>(i)];
        Vec2 uv;
        EXPECT_TRUE(cam->project(truth.rotation().transpose() * (p - truth.t), uv));
        uv += params.sigmaPx * Vec2(gauss(rng), gauss(rng));
        if (i == 0) uv0 = uv;
        else z.emplace_back(i, uv);
      }
      map.add(k, z);
      return uv0;
    };
    track.start(0, observe(0));
    for (int k = 1; k <= kFrames; ++k)
    {
      advanceWithNoisyIncrement(rng, drift, Cactual, Cinc, k, truth, track);
      if (k == kFrames / 2 || k == kFrames) track.addView(observe(k));
    }
    const TRayTestResult r = cls.test(track);
    if (!r.evaluated) continue;
    ++evaluated;
    alone += r.test.test.rejected();
    withMap += r.test.test.T > cls.mapScale(track, r, map) * r.test.test.threshold;
  }
  EXPECT_GE(evaluated, trials - 10);
  return {double(alone) / evaluated, double(withMap) / evaluated};
}
}  // namespace

TEST(ShadowClassifier, TheMapAbsorbsAnOverConfidentRelativeMotion)
{
  // The relative poses' covariance understates their error (an EKF's composed increments on real
  // video): static points are rejected far above alpha. The map's points measured in the same frames
  // see the same error; scaled by their median statistic the test is near alpha again, and a point
  // that moves across its ray at 2 px per frame is still rejected. With a right covariance the map
  // changes little (the scale is never below 1; the median of 8 chi-square values exceeds that of
  // chi-square(3) half the time, so the rate drops below alpha and the power a little).
  // Measured (500 trials each, seeds 11-14), alone / against the map: right covariance, static 3.2 /
  // 1.2 %, mover 92.0 / 90.8 %; covariance 4x too small (error 4x the stated sigma), static 63.6 /
  // 1.0 %, mover 95.8 / 80.0 %. Bands: 3 binomial sigmas (n = 500) around the measured rates where
  // they are the point (static against the map <= alpha; movers), the problem itself shown (alone
  // static, over-confident, >= 40 %).
  const int n = 500;
  const auto [consistentAlone, consistentMap] = rejectionRates(1.0, 0.0, n, 11);
  const auto [staticAlone, staticMap] = rejectionRates(4.0, 0.0, n, 12);
  const auto [moverAlone, moverMap] = rejectionRates(4.0, 2.0, n, 13);
  const auto [slowAlone, slowMap] = rejectionRates(1.0, 2.0, n, 14);
  std::printf("[ shadow   ] rejection rate alone / with the map: consistent poses static %.3f / %.3f, mover %.3f / %.3f; "
              "poses 4x over-confident static %.3f / %.3f, mover %.3f / %.3f\n",
              consistentAlone, consistentMap, slowAlone, slowMap, staticAlone, staticMap, moverAlone, moverMap);
  EXPECT_LE(consistentMap, 0.05);
  EXPECT_LE(consistentMap, consistentAlone);
  EXPECT_GE(slowMap, 0.87);
  EXPECT_GE(staticAlone, 0.40);
  EXPECT_LE(staticMap, 0.05);
  EXPECT_GE(moverMap, 0.74);
}

TEST(CMapViews, KeepsRecentFramesAndFindsPointsSeenInAllThree)
{
  CMapViews map;
  for (std::int64_t k = 0; k < static_cast<std::int64_t>(CMapViews::kFrames) + 5; ++k)
  {
    std::vector<std::pair<std::int64_t, Vec2>> z;
    for (std::int64_t id = 20; id >= 0; --id)  // unsorted on purpose
      if (id % 2 == 0 || k % 2 == 0) z.emplace_back(id, Vec2(double(id), double(k)));
    map.add(k, z);
  }
  // Frames 0-4 are gone; ids 0..20 even are in every frame, odd ones only in even frames.
  EXPECT_TRUE(map.common({0, 10, 20}, 100).empty());
  const auto even = map.common({10, 11, 12}, 100);
  ASSERT_EQ(even.size(), 11u);
  EXPECT_EQ(even[3][0], Vec2(6, 10));
  EXPECT_EQ(even[3][1], Vec2(6, 11));
  EXPECT_EQ(even[3][2], Vec2(6, 12));
  EXPECT_EQ(map.common({10, 12, 14}, 100).size(), 21u);
  const auto few = map.common({10, 12, 14}, 4);  // spread over the ids
  ASSERT_EQ(few.size(), 4u);
  EXPECT_EQ(few[0][0].x(), 0);
  EXPECT_GT(few[3][0].x(), 10);
  map.add(7, {});  // an older frame than the last is ignored
  EXPECT_EQ(map.common({10, 12, 14}, 100).size(), 21u);
}

namespace
{
/** Static points seen by a hand-held camera (known association, 1 px noise, 150 frames); in frames 20-23 the
 * SLAM lost track and gave its prediction, then in frame 24 a relocalisation moved it back: the
 * increments of those frames are wrong (the camera held still, then jumped by the motion it made)
 * with the small covariance of a velocity estimate, as a lost filter states them. `measured`: what
 * TCameraMotion::measured says in those frames. Returns (static points decided dynamic, decided
 * static, decisions made in frames 20-24). */
std::array<int, 3> runThroughALoss(bool measured, unsigned seed)
{
  const auto cam = simCamera();
  CShadowFilter::TOptions opts;
  CShadowFilter filter(opts, cam);
  Rng rng(seed);
  const THandheldPath path = randomHandheldPath(rng, 0.01);
  std::vector<TPose> poses(150);
  for (int k = 0; k < 150; ++k) poses[k] = {path.position(k), path.orientation(k)};
  std::vector<Vec3> pts;
  while (pts.size() < 30)
  {
    const Vec2 px(uniform(rng, 20, 300), uniform(rng, 20, 220));
    pts.push_back(poses[0].r + poses[0].R() * (cam->unproject(px).unitVector() * uniform(rng, 1.5, 4.0)));
  }
  std::map<std::int64_t, std::size_t> byId;
  std::array<int, 3> out{0, 0, 0};
  const Mat6 cov = Mat6::Identity() * 1e-8;
  Vec3 lastR = poses[0].r;
  Vec4 lastQ = poses[0].q;
  for (int k = 0; k < 150; ++k)
  {
    const bool lost = k >= 20 && k <= 23, relocalised = k == 24;
    // The camera the shadow filter is told about: still while lost, back on its path when relocalised.
    const Vec3 r = lost ? lastR : poses[k].r;
    const Vec4 q = lost ? lastQ : poses[k].q;
    TCameraMotion m = TCameraMotion::FromPoses(lastR, lastQ, r, q);
    lastR = r;
    lastQ = q;
    m.frame = k;
    m.timestamp = k / 30.0;
    m.cov_increment = cov;
    m.measured = measured || !(lost || relocalised);
    std::vector<std::pair<std::int64_t, Vec2>> z;
    for (const auto& [id, i] : byId)
    {
      Vec2 uv;
      if (cam->project(poses[k].toCamera(pts[i]), uv) && cam->isInImage(uv, 2))
        z.emplace_back(id, uv + Vec2(gauss(rng), gauss(rng)));
    }
    const TShadowReport& rep = filter.processMeasurements(m, z);
    for (const auto& d : rep.decisions)
    {
      ++out[d.cls == EShadowClass::Dynamic ? 0 : 1];
      out[2] += k >= 20 && k <= 24;
    }
    if (k == 0) byId = addSeenPoints(filter, *cam, poses[0], pts);
  }
  return out;
}
}  // namespace

TEST(ShadowFilter, NothingIsDecidedOnACameraMotionTheSlamDidNotMeasure)
{
  // A lost SLAM's pose is its prediction, and the relocalisation that ends the loss moves it at once:
  // increments that are no motion, stated with a velocity's small covariance. Taken as motion they
  // make static points look dynamic; flagged unmeasured (TCameraMotion::measured), nothing is tested
  // in those frames and the views start again after them. Measured (seeds 3-5, 30 static points
  // each, 150 frames): taken as motion 17 of 90 decided dynamic and 46 static (some of them on the
  // jump's false parallax); flagged 2 dynamic (alpha's share) and 48 static.
  std::array<int, 3> asMotion{0, 0, 0}, flagged{0, 0, 0};
  for (unsigned seed = 3; seed <= 5; ++seed)
  {
    const auto a = runThroughALoss(true, seed), b = runThroughALoss(false, seed);
    for (int i = 0; i < 3; ++i)
    {
      asMotion[i] += a[i];
      flagged[i] += b[i];
    }
  }
  std::printf("[ shadow   ] through a loss of tracking, static points decided dynamic / static: taken as motion %d / %d, "
              "flagged unmeasured %d / %d (decisions in the lost frames: %d)\n",
              asMotion[0], asMotion[1], flagged[0], flagged[1], flagged[2]);
  EXPECT_GE(asMotion[0], 10) << "the case the flag is for: the jump taken as motion";
  EXPECT_EQ(flagged[2], 0);
  EXPECT_LE(flagged[0], 4);   // 5 % of the 90 points
  EXPECT_GE(flagged[1], 40);  // the views that start again still reach static decisions
}
