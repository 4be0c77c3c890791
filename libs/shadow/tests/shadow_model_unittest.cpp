/* Tests: the shadow filter's models — relative poses, eq. (2) transition, eqs. (3)-(5) measurement,
 * gauge, ray construction (every analytic Jacobian against a numerical one), the non-central
 * chi-square, options. */
#include <gtest/gtest.h>
#include <immslam/core/config.h>
#include <immslam/math/numerical_jacobian.h>
#include <immslam/shadow/CRayClassifier.h>
#include <immslam/shadow/CShadowFilter.h>
#include <immslam/shadow/feature_ekf.h>
#include <immslam/shadow/relative_pose.h>

#include <mrpt/config/CConfigFileMemory.h>

#include <algorithm>

#include "shadow_test_utils.h"

using namespace immslam;
using namespace immslam::shadow;
using namespace immslam::shadow::test;

namespace
{
TUncertainPose randomPose(Rng& rng, double tScale = 1.0)
{
  TUncertainPose p;
  p.t = tScale * gauss3(rng);
  p.q = math::quatFromRotationVector(0.5 * gauss3(rng));
  Eigen::Matrix<double, 6, 6> A = Eigen::Matrix<double, 6, 6>::Random();
  p.cov = 1e-4 * A * A.transpose();
  return p;
}

void expectNear(const MatX& a, const MatX& b, double tol, const char* what)
{
  ASSERT_EQ(a.rows(), b.rows()) << what;
  ASSERT_EQ(a.cols(), b.cols()) << what;
  EXPECT_LT((a - b).cwiseAbs().maxCoeff(), tol) << what << "\nanalytic:\n" << a << "\nnumerical:\n" << b;
}
}  // namespace

TEST(ShadowRelativePose, CompositionJacobians)
{
  Rng rng(1);
  for (int trial = 0; trial < 20; ++trial)
  {
    const TUncertainPose a = randomPose(rng), b = randomPose(rng);
    Mat6 Ja, Jb;
    const TUncertainPose ab = composePoses(a, b, &Ja, &Jb);
    const auto fa = [&](const VecX& d)
    {
      const TUncertainPose c = composePoses(perturbPose(a, d), b);
      return VecX(posePerturbation(ab.t, ab.q, c.t, c.q));
    };
    const auto fb = [&](const VecX& d)
    {
      const TUncertainPose c = composePoses(a, perturbPose(b, d));
      return VecX(posePerturbation(ab.t, ab.q, c.t, c.q));
    };
    expectNear(Ja, math::numericalJacobian(fa, VecX::Zero(6)), 1e-7, "J_ab_a");
    expectNear(Jb, math::numericalJacobian(fb, VecX::Zero(6)), 1e-7, "J_ab_b");
    expectNear(ab.cov, Ja * a.cov * Ja.transpose() + Jb * b.cov * Jb.transpose(), 1e-15, "cov");
    // The inverse mean.
    const TUncertainPose I = composePoses(a, a.inverseMean());
    EXPECT_LT(I.t.norm(), 1e-12);
    EXPECT_LT(math::quatToRotationVector(I.q).norm(), 1e-12);
  }
}

TEST(ShadowRelativePose, PerturbationTransport)
{
  Rng rng(2);
  for (int trial = 0; trial < 20; ++trial)
  {
    const TUncertainPose T0m = randomPose(rng), Tmk = randomPose(rng);
    const TUncertainPose T0k = composePoses(T0m, Tmk);
    const Mat6 Phi = perturbationTransport(T0m, T0k);
    const auto f = [&](const VecX& d)
    {
      const TUncertainPose c = composePoses(perturbPose(T0m, d), Tmk);
      return VecX(posePerturbation(T0k.t, T0k.q, c.t, c.q));
    };
    expectNear(Phi, math::numericalJacobian(f, VecX::Zero(6)), 1e-7, "Phi");
  }
}

TEST(ShadowFeatureEkf, TransitionJacobians)
{
  Rng rng(3);
  for (int trial = 0; trial < 20; ++trial)
  {
    Vec7 x;
    x << randomUnit(rng), uniform(rng, -0.5, 2.0), 0.05 * gauss3(rng);
    const double dt = uniform(rng, 0.5, 3);
    const Vec3 t = 0.05 * gauss3(rng);
    const Vec4 dq = math::quatFromRotationVector(0.05 * gauss3(rng));
    Mat7 Jx;
    Mat76 Jinc;
    Mat73 JV;
    const Vec7 y = shadowTransition(x, dt, t, dq, &Jx, &Jinc, &JV);
    const auto fx = [&](const VecX& xx) { return VecX(shadowTransition(Vec7(xx), dt, t, dq)); };
    expectNear(Jx, math::numericalJacobian(fx, x), 1e-8, "J_x");
    const auto finc = [&](const VecX& d)
    {
      TUncertainPose inc;
      inc.t = t;
      inc.q = dq;
      const TUncertainPose p = perturbPose(inc, Vec6(d));
      return VecX(shadowTransition(x, dt, p.t, p.q));
    };
    expectNear(Jinc, math::numericalJacobian(finc, VecX::Zero(6)), 1e-8, "J_inc");
    // V is a Euclidean velocity impulse: v + V, i.e. u + w V.
    const auto fV = [&](const VecX& V)
    {
      Vec7 xv = x;
      xv.segment<3>(kVel) += x[kW] * V;  // u = w v
      return VecX(shadowTransition(xv, dt, t, dq));
    };
    expectNear(JV, math::numericalJacobian(fV, VecX::Zero(3)), 1e-8, "J_V");
    // The Euclidean point moves as the camera-relative motion says (w > 0).
    if (x[kW] > 0.1)
    {
      const Vec3 p = x.head<3>() / x[kW];
      const Vec3 v = x.segment<3>(kVel) / x[kW];
      const Vec3 pNew = math::quatToRotation(dq).transpose() * (p + v * dt - t);
      EXPECT_LT((y.head<3>() / y[kW] - pNew).norm(), 1e-9);
      EXPECT_LT((y.segment<3>(kVel) / y[kW] - math::quatToRotation(dq).transpose() * v).norm(), 1e-9);
    }
  }
}

TEST(ShadowFeatureEkf, MeasurementGaugeAndPositionJacobians)
{
  Rng rng(4);
  for (const auto& cam : {simCamera(), distortedCamera()})
    for (int trial = 0; trial < 20; ++trial)
    {
      Vec7 x;
      x << Vec3(uniform(rng, -0.5, 0.5), uniform(rng, -0.4, 0.4), 1.0).normalized() * uniform(rng, 0.5, 2),
          uniform(rng, 0.1, 2.0), gauss3(rng);
      Vec2 uv;
      Mat27 H;
      ASSERT_TRUE(shadowMeasurement(*cam, x, uv, &H));
      const auto fh = [&](const VecX& xx)
      {
        Vec2 u;
        shadowMeasurement(*cam, Vec7(xx), u);
        return VecX(u);
      };
      expectNear(H, math::numericalJacobian(fh, x), 1e-5, "H");
      Mat7 Jg;
      const Vec7 xn = normalizeGauge(x, &Jg);
      EXPECT_NEAR(xn.head<3>().norm(), 1.0, 1e-12);
      const auto fg = [&](const VecX& xx) { return VecX(normalizeGauge(Vec7(xx))); };
      expectNear(Jg, math::numericalJacobian(fg, x), 1e-8, "J_gauge");
      EXPECT_LT((Jg * x).norm(), 1e-12);
      EXPECT_LT((xn.segment<3>(kVel) / xn[kW] - x.segment<3>(kVel) / x[kW]).norm(), 1e-12);
      TShadowState s;
      s.x = xn;
      Eigen::Matrix<double, 3, 7> Jp;
      const Vec3 p = shadowPosition(s, 1e-3, nullptr, &Jp);
      EXPECT_LT((p - x.head<3>() / x[kW]).norm(), 1e-9);
      const auto fp = [&](const VecX& xx)
      {
        TShadowState ss;
        ss.x = xx;
        return VecX(shadowPosition(ss));
      };
      expectNear(Jp, math::numericalJacobian(fp, xn), 1e-6, "J_p");
      Eigen::Matrix<double, 3, 7> Jv;
      const Vec3 vel = shadowVelocity(s, 1e-3, nullptr, &Jv);
      EXPECT_LT((vel - x.segment<3>(kVel) / x[kW]).norm(), 1e-9);
      const auto fv = [&](const VecX& xx)
      {
        TShadowState ss;
        ss.x = xx;
        return VecX(shadowVelocity(ss));
      };
      expectNear(Jv, math::numericalJacobian(fv, xn), 1e-6, "J_v");
    }
}

TEST(ShadowFeatureEkf, InitialisationAndUpdateShrinkUncertainty)
{
  const auto cam = distortedCamera();
  const Vec2 uv(400, 300);
  const TShadowState s0 = initialiseShadowState(*cam, uv, 1.0, 1.0, 1.0, 0.02);
  Vec2 h;
  Mat2 S;
  ASSERT_TRUE(shadowInnovation(s0, *cam, 1.0, h, S));
  EXPECT_LT((h - uv).norm(), 1e-9);
  // The ray's uncertainty is the pixel noise: S = 2 sigma^2 I.
  EXPECT_LT((S - 2 * Mat2::Identity()).norm(), 1e-6);
  TShadowState s = s0;
  predictShadowState(s, 1, Vec3(0.05, 0, 0), Vec4(1, 0, 0, 0), 1e-8 * Mat6::Identity(), 0.001);
  EXPECT_NEAR(s.x.head<3>().norm(), 1, 1e-12);
  ASSERT_TRUE(shadowInnovation(s, *cam, 1.0, h, S));
  const double area0 = S.determinant();
  ASSERT_TRUE(updateShadowState(s, *cam, h + Vec2(1, -1), 1.0));
  ASSERT_TRUE(shadowInnovation(s, *cam, 1.0, h, S));
  EXPECT_LT(S.determinant(), area0);
  EXPECT_TRUE(s.P.allFinite());
  Eigen::SelfAdjointEigenSolver<Mat7> es(s.P);
  EXPECT_GT(es.eigenvalues()[0], -1e-12);
}

TEST(ShadowRayClassifier, ViewRayJacobians)
{
  Rng rng(5);
  const auto cam = distortedCamera();
  const CRayClassifier cls(TRayClassifierParams(), cam);
  for (int trial = 0; trial < 20; ++trial)
  {
    TRayView v;
    v.uv = Vec2(uniform(rng, 50, 590), uniform(rng, 50, 430));
    v.T_0j = randomPose(rng);
    Eigen::Matrix<double, 6, 2> Ju;
    Mat6 Jp;
    const Vec6 L = cls.viewRay(v, &Ju, &Jp);
    EXPECT_NEAR(L.head<3>().dot(L.tail<3>()), 0, 1e-12);  // Plücker constraint
    const auto fu = [&](const VecX& uv)
    {
      TRayView w = v;
      w.uv = uv;
      return VecX(cls.viewRay(w));
    };
    const auto fp = [&](const VecX& d)
    {
      TRayView w = v;
      w.T_0j = perturbPose(v.T_0j, Vec6(d));
      return VecX(cls.viewRay(w));
    };
    expectNear(Ju, math::numericalJacobian(fu, v.uv, 1e-4), 1e-6, "J_L_uv");
    expectNear(Jp, math::numericalJacobian(fp, VecX::Zero(6)), 1e-7, "J_L_pose");
  }
}

TEST(ShadowRayClassifier, NoncentralChiSquare)
{
  // Central case and textbook values (1 dof: (Z + sqrt(lambda))^2).
  EXPECT_NEAR(noncentralChi2Cdf(7.815, 3, 0), 0.95, 1e-4);
  EXPECT_NEAR(noncentralityForPower(0.05, 1, 0.5), 3.84, 0.01);
  EXPECT_NEAR(noncentralityForPower(0.05, 1, 0.8), 7.85, 0.01);
  // Monte Carlo check of 3 dof.
  Rng rng(6);
  const double lambda = noncentralityForPower(0.05, 3, 0.95);
  int rejected = 0;
  const int n = 200000;
  for (int i = 0; i < n; ++i)
  {
    const Vec3 z = gauss3(rng) + Vec3(std::sqrt(lambda), 0, 0);
    rejected += z.squaredNorm() > 7.8147279;
  }
  report("lambda for power 0.95 at alpha 0.05, 3 dof", lambda);
  EXPECT_NEAR(double(rejected) / n, 0.95, 0.003);
}

TEST(ShadowOptions, LoadSaveAndErrors)
{
  CShadowFilter::TOptions o;
  mrpt::config::CConfigFileMemory c;
  o.sigma_accel_px = 0.25;
  o.max_features = 70;
  o.decide_lone_dynamic = true;
  o.saveToConfigFile(c, "shadow");
  std::string text;
  c.getContent(text);  // (MRPT 2.5.8's CConfigFileMemory does not read back its own writes)
  CShadowFilter::TOptions o2;
  o2.loadFromConfigFile(mrpt::config::CConfigFileMemory(text), "shadow");
  EXPECT_EQ(o2.sigma_accel_px, 0.25);
  EXPECT_EQ(o2.max_features, 70);
  EXPECT_TRUE(o2.decide_lone_dynamic);
  // Noise, prior and search come from [slam] and [search]; the classifier's and the track management's
  // internals are constants (TOptions::k*), not keys.
  EXPECT_EQ(core::knownKeys(o, "shadow").size(), 3u);
  EXPECT_THROW(o2.loadFromConfigFile(mrpt::config::CConfigFileMemory("[shadow]\nmax_features = 0\n"), "shadow"),
               std::runtime_error);
  EXPECT_THROW(o2.loadFromConfigFile(mrpt::config::CConfigFileMemory("[shadow]\nsigma_accel_px = abc\n"), "shadow"),
               std::runtime_error);
  EXPECT_THROW(o2.loadFromConfigFile(mrpt::config::CConfigFileMemory("[shadow]\ndecide_lone_dynamic = maybe\n"),
                                     "shadow"),
               std::runtime_error);
  EXPECT_THROW(CShadowFilter(CShadowFilter::TOptions(), nullptr), std::runtime_error);
}

TEST(ShadowCameraMotion, FromPosesMatchesConvention)
{
  Rng rng(7);
  const Vec3 r0 = gauss3(rng), r1 = gauss3(rng);
  const Vec4 q0 = math::quatFromRotationVector(gauss3(rng)), q1 = math::quatFromRotationVector(gauss3(rng));
  const TCameraMotion m = TCameraMotion::FromPoses(r0, q0, r1, q1);
  const Vec3 pC1 = gauss3(rng);
  const Vec3 pW = math::quatToRotation(q1) * pC1 + r1;
  const Vec3 pC0 = math::quatToRotation(q0).transpose() * (pW - r0);
  EXPECT_LT((pC0 - (math::quatToRotation(m.dq) * pC1 + m.t)).norm(), 1e-12);
}

namespace
{
/** A track of a point seen from a hand-held path at frames 0..n-1 (exact pixels unless noisy), the
 * point at p0 + vel * k (W). */
TRayTrack makeTrack(const camera::CCameraModel& cam, const THandheldPath& path, const Vec3& p0, const Vec3& vel, int n,
                    const Mat6& covInc)
{
  TRayTrack tr;
  for (int k = 0; k < n; ++k)
  {
    const TPose P{path.position(k), path.orientation(k)};
    Vec2 uv;
    EXPECT_TRUE(cam.project(P.toCamera(p0 + vel * k), uv));
    if (k == 0)
    {
      tr.start(0, uv);
      continue;
    }
    const TPose Q{path.position(k - 1), path.orientation(k - 1)};
    const TCameraMotion m = TCameraMotion::FromPoses(Q.r, Q.q, P.r, P.q);
    tr.advance(k, 1, m.t, m.dq, covInc);
    tr.addView(uv);
  }
  return tr;
}
}  // namespace

TEST(ShadowRayClassifier, VelocityNoncentralityMatchesTheTest)
{
  // lambda(V) = V^T A V must predict threeRaysMeet's statistic on exact rays of a point moving at V.
  Rng rng(8);
  const auto cam = simCamera();
  const CRayClassifier cls(TRayClassifierParams(), cam);
  Mat6 covInc = Mat6::Zero();
  covInc.diagonal() << Vec3::Constant(1e-6), Vec3::Constant(2.5e-7);
  int checked = 0;
  std::vector<double> ratios;
  for (int trial = 0; trial < 30; ++trial)
  {
    const THandheldPath path = randomHandheldPath(rng, 0.4 / 30);
    const TPose P0{path.position(0), path.orientation(0)};
    const Vec3 p0 = P0.r + P0.R() * (Vec3(uniform(rng, -0.4, 0.4), uniform(rng, -0.3, 0.3), 1) * uniform(rng, 1, 4));
    const int n = 40;
    const TRayTrack still = makeTrack(*cam, path, p0, Vec3::Zero(), n, covInc);
    const TRayTestResult r0 = cls.test(still);
    ASSERT_TRUE(r0.evaluated);
    EXPECT_LT(r0.test.test.T, 1e-6);
    Mat3 A;
    double dist = 0;
    ASSERT_TRUE(cls.velocityNoncentrality(still, r0, A, &dist));
    for (int d = 0; d < 3; ++d)
    {
      const Vec3 e = randomUnit(rng);
      const double lam = e.dot(A * e);
      ASSERT_GT(lam, 0);
      // Small motions (statistic 0.01): the linearization must be exact to first order. At a
      // statistic of 10 (where power is decided) the test's own nonlinearity shows: reported.
      for (const double target : {0.01, 10.0})
      {
        const Vec3 V_C0 = std::sqrt(target / lam) * e;
        const TRayTrack moving = makeTrack(*cam, path, p0, P0.R() * V_C0, n, covInc);
        const TRayTestResult r = cls.test(moving);
        ASSERT_TRUE(r.evaluated);
        const double ratio = r.test.test.T / V_C0.dot(A * V_C0);
        if (target < 1)
          EXPECT_NEAR(ratio, 1.0, 0.05) << "trial " << trial;
        else
          ratios.push_back(ratio);
      }
      ++checked;
    }
    // Worst-direction detectable speed and the detection probability are consistent.
    const double mdv = cls.minimumDetectableVelocityPx(still, r0);
    EXPECT_NEAR(cls.detectionProbability(still, r0, mdv), 0.95, 1e-3);
  }
  EXPECT_GE(checked, 60);
  std::sort(ratios.begin(), ratios.end());
  std::printf("[ shadow   ] test statistic / predicted non-centrality at 10: 10%% %.2f, median %.2f, 90%% %.2f\n",
              ratios[ratios.size() / 10], ratios[ratios.size() / 2], ratios[9 * ratios.size() / 10]);
  EXPECT_NEAR(ratios[ratios.size() / 2], 1.0, 0.2);
}

TEST(ShadowFilter, TrackPointCovarianceJacobian)
{
  const auto cam = simCamera();
  CShadowFilter filter(CShadowFilter::TOptions(), cam);
  TCameraMotion m;
  m.r_W_C = Vec3(0.3, -0.2, 0.1);
  m.q_W_C = math::quatFromRotationVector(Vec3(0.1, -0.3, 0.2));
  m.cov_W_C.diagonal() << 1e-4, 2e-4, 3e-4, 1e-5, 2e-5, 3e-5;
  filter.processMeasurements(m, {});
  const auto id = filter.addFeatures({Vec2(100, 80)})[0];
  ASSERT_GE(id, 0);
  m.frame = 1;
  m.t = Vec3(0.02, 0, 0);
  filter.processMeasurements(m, {{id, Vec2(99, 80)}});
  const TShadowFeature* f = filter.feature(id);
  ASSERT_NE(f, nullptr);
  const TTrackPoint tp = filter.trackPoint(*f);
  Mat3 covC;
  const Vec3 pC = shadowPosition(f->ekf, filter.options().min_inverse_distance, &covC);
  const auto g = [&](const VecX& d)
  {
    TUncertainPose T;
    T.t = m.r_W_C;
    T.q = m.q_W_C;
    const TUncertainPose Tp = perturbPose(T, Vec6(d));
    return VecX(Tp.transform(pC));
  };
  const MatX J = math::numericalJacobian(g, VecX::Zero(6));
  const Mat3 R = math::quatToRotation(m.q_W_C);
  const MatX expected = R * covC * R.transpose() + J * m.cov_W_C * J.transpose();
  expectNear(tp.cov_W, expected, 1e-9, "cov_W");
  EXPECT_LT((tp.p_W - (m.r_W_C + R * pC)).norm(), 1e-12);
}

TEST(ShadowFilter, BookkeepingAndIds)
{
  const auto cam = simCamera();
  CShadowFilter::TOptions opts;
  opts.max_features = 3;
  std::int64_t next = 500;
  CShadowFilter filter(opts, cam, [&] { return next++; });
  TCameraMotion m;
  filter.processMeasurements(m, {});
  const auto ids = filter.addFeatures({Vec2(50, 50), Vec2(100, 60), Vec2(200, 70), Vec2(250, 80)});
  ASSERT_EQ(ids.size(), 4u);
  EXPECT_EQ(ids[0], 500);
  EXPECT_EQ(ids[2], 502);
  EXPECT_EQ(ids[3], -1);  // max_features
  EXPECT_EQ(filter.numPending(), 3u);
  EXPECT_EQ(filter.occupiedPixels().size(), 3u);
  // Unknown ids are ignored; unmatched features count as missed and are lost after max_missed_frames.
  for (int k = 1; k <= opts.max_missed_frames + 1; ++k)
  {
    m.frame = k;
    const TShadowReport& rep = filter.processMeasurements(m, {{ids[0], Vec2(50, 50)}, {12345, Vec2(1, 1)}});
    EXPECT_EQ(rep.nMeasured, 1);
    EXPECT_EQ(rep.nLost, k <= opts.max_missed_frames ? 0 : 2);
  }
  EXPECT_EQ(filter.size(), 1u);
  filter.removeFeatures({ids[0]});
  EXPECT_EQ(filter.size(), 0u);
  // Bad inputs.
  m.dt = 0;
  EXPECT_THROW(filter.processMeasurements(m, {}), std::runtime_error);
  // Without an id allocator, ids start at kFirstOwnId.
  CShadowFilter other(opts, cam);
  EXPECT_EQ(other.addFeatures({Vec2(10, 10)})[0], CShadowFilter::kFirstOwnId);
}

TEST(ShadowFilter, ReleaseKeepsTheFeaturesItIsToldToKeep)
{
  // releaseUnresolved() never releases the ids it is told to keep (the system's probation copies of
  // first-map features, which SLAM holds already).
  const auto cam = simCamera();
  CShadowFilter::TOptions opts;
  std::int64_t next = 700;
  CShadowFilter filter(opts, cam, [&] { return next++; });
  TCameraMotion m;
  filter.processMeasurements(m, {});
  const auto ids = filter.addFeatures({Vec2(50, 50), Vec2(100, 60), Vec2(150, 70)});
  ASSERT_EQ(ids, (std::vector<std::int64_t>{700, 701, 702}));
  // Still camera, every feature measured where it was for 12 frames: all releasable but 700.
  for (int k = 1; k <= 12; ++k)
  {
    m.frame = k;
    filter.processMeasurements(m, {{700, Vec2(50, 50)}, {701, Vec2(100, 60)}, {702, Vec2(150, 70)}});
  }
  const auto rel = filter.releaseUnresolved(10, 10, {700});
  ASSERT_EQ(rel.size(), 2u);
  EXPECT_EQ(rel[0].id, 701);
  EXPECT_EQ(rel[1].id, 702);
  EXPECT_NE(filter.feature(700), nullptr);
}
