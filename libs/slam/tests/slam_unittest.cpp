/* Tests of the SLAM filter: measurement Jacobians through every camera model, structural state
 * operations, the pose correction of relocalisation, and consistency (NEES) on a measurement-level Monte Carlo simulation.
 * 1-point RANSAC and the high-innovation rescue are tested in ransac_unittest.cpp, deletion and
 * ID -> XYZ conversion in libs/tracking/tests/map_management_unittest.cpp, the relocaliser on images in
 * libs/tracking/tests/tracker_image_unittest.cpp. */
#include <gtest/gtest.h>
#include <immslam/features/inverse_depth.h>
#include <immslam/math/chi2.h>
#include <immslam/math/numerical_jacobian.h>
#include <immslam/math/quaternion.h>
#include <immslam/tracking/CMonoSlamIMM.h>
#include <immslam/slam/measurement.h>
#include <immslam/slam/robocentric_prediction.h>
#include <immslam/slam/state_ops.h>


#include <limits>
#include <random>

#include "../../motion/tests/world_motion_model.h"  // ground truth of the simulations
#include "slam_test_utils.h"

using namespace immslam;
using namespace immslam::slam;
using immslam::slam::test::randomCovariance;

namespace
{
std::vector<camera::CCameraModel::Ptr> allCameras()
{
  return {camera::makeCameraModel("pinhole", 320, 240, {200, 200, 160, 120}),
          camera::makeCameraModel("opencv", 752, 480, {458.654, 457.296, 367.215, 248.375, -0.2834, 0.0740, 0.00019, 1.76e-05, 0}),
          camera::makeCameraModel("davison", 320, 240, {195, 195, 162, 125, 9e-6})};
}

/** A state with a camera and one ID and one XYZ feature, all visible. */
struct TToyState
{
  VecX x;
  std::vector<TFeature> feats;
  TToyState()
  {
    x = VecX::Zero(13 + 6 + 3);
    x.segment<3>(0) = Vec3(0.05, -0.02, 0.1);
    x.segment<4>(3) = math::quatFromRotationVector(Vec3(0.02, -0.05, 0.03));
    x.segment<6>(13) << 0.01, 0.02, -0.01, 0.1, -0.05, 0.4;
    x.segment<3>(19) << -0.3, 0.2, 2.5;
    TFeature a, b;
    a.offset = 13;
    b.kind = EFeatureKind::XYZ;
    b.offset = 19;
    feats = {a, b};
  }
};
}  // namespace

TEST(Measurement, JacobiansThroughEveryCameraModel)
{
  TToyState s;
  for (const auto& cam : allCameras())
    for (const auto& f : s.feats)
    {
      Vec2 uv;
      Mat2F Jf;
      ASSERT_TRUE(predictMeasurement(*cam, s.x, f, uv, &Jf)) << cam->modelName();
      const MatX Jn = math::numericalJacobian(
          [&](const VecX& v) -> VecX {
            Vec2 u;
            predictMeasurement(*cam, v, f, u);
            return u;
          },
          s.x, 1e-7);
      EXPECT_LT((Jn.middleCols(f.offset, f.dim()) - Jf).norm(), 1e-4 * (1 + Jf.norm())) << cam->modelName();
      // Camera-centred: the pixel depends on the feature block only.
      EXPECT_LT(Jn.leftCols(13).norm(), 1e-9);
    }
}

TEST(Measurement, WorldPoseInversionJacobian)
{
  TToyState s;
  Vec3 r;
  Vec4 q;
  Eigen::Matrix<double, 7, 7> J;
  worldPoseFromState(s.x, r, q, &J);
  // T_W_C composed with T_C_W is the identity.
  const Vec3 back = math::quatRotate(s.x.segment<4>(3), r) + s.x.segment<3>(0);
  EXPECT_LT(back.norm(), 1e-12);
  const MatX Jn = math::numericalJacobian(
      [](const VecX& v) -> VecX {
        VecX x = VecX::Zero(13);
        x.head<7>() = v;
        Vec3 rr;
        Vec4 qq;
        worldPoseFromState(x, rr, qq);
        VecX o(7);
        o << rr, qq;
        return o;
      },
      VecX(s.x.head<7>()));
  EXPECT_LT((Jn - J).norm(), 1e-7);
}

namespace
{
/** The toy state with non-zero velocities. */
TToyState movingToyState()
{
  TToyState s;
  s.x.segment<3>(7) << 0.01, -0.02, 0.015;
  s.x.segment<3>(10) << 0.02, 0.01, -0.03;
  return s;
}
/** The increment of one model (a TIMMBankOptions spec, e.g. "general:1") at the toy state's velocities. */
motion::TMotionIncrement toyIncrement(const TToyState& s, const char* spec, double shakePx = 0.0)
{
  TIMMBankOptions b;
  b.models = spec;
  b.shake_px = shakePx;
  return motion::motionIncrement(b.parseModels()[0], s.x.segment<3>(7), s.x.segment<3>(10), 1.0, 200);
}
}  // namespace

TEST(Prediction, CamCentredCovarianceMatchesNumericalTransition)
{
  // P' = A (P + E N E^T) A^T with A the Jacobian of the whole transition x' = f(x).
  const TToyState s = movingToyState();
  std::mt19937 rng(9);
  const int n = static_cast<int>(s.x.size());
  const MatX P0 = randomCovariance(n, rng);
  for (const auto* spec : {"general:1", "rotation:0.5", "stationary"})
  {
    TIMMBankOptions b;
    b.models = spec;
    b.shake_px = 0;  // the shake's own term: ShakeIsARotationAfterTheMotion
    const auto model = b.parseModels()[0];
    const auto f = [&](const VecX& x) -> VecX {
      bayes::TGaussian G{x, MatX::Zero(n, n)};
      MatX scratch;
      const auto inc = motion::motionIncrement(model, x.segment<3>(7), x.segment<3>(10), 1.0, 200);
      predictRobocentric(G, s.feats, inc, scratch);
      return G.x;
    };
    const MatX F = math::numericalJacobian(f, s.x, 1e-7);
    const auto inc = motion::motionIncrement(model, s.x.segment<3>(7), s.x.segment<3>(10), 1.0, 200);
    MatX Pt = P0;
    Pt.block<6, 6>(7, 7) += inc.noiseCov;
    bayes::TGaussian G{s.x, P0};
    MatX scratch;
    predictRobocentric(G, s.feats, inc, scratch);
    EXPECT_LT((G.x - f(s.x)).norm(), 1e-15) << spec;
    EXPECT_LT((G.P - F * Pt * F.transpose()).norm(), 1e-6 * P0.norm()) << spec;
    EXPECT_LT((G.P - G.P.transpose()).norm(), 1e-15) << spec;
  }
}

TEST(Prediction, LazyTransitionBlocksMatchTheFullPrediction)
{
  // The deferred form (mean + transition blocks + P~) gives the same blocks, columns and H P' H^T as
  // the full prediction, and applying it later gives the same P'.
  const TToyState s = movingToyState();
  std::mt19937 rng(19);
  std::normal_distribution<double> g;
  const int n = static_cast<int>(s.x.size());
  const MatX P0 = randomCovariance(n, rng);
  for (const auto* spec : {"general:1", "rotation:0.5"})
  {
    const auto inc = toyIncrement(s, spec);
    bayes::TGaussian full{s.x, P0}, lazy{s.x, P0};
    MatX scratch;
    predictRobocentric(full, s.feats, inc, scratch);
    std::vector<TTransitionBlock> blocks;
    predictRobocentricMean(lazy, s.feats, inc, blocks);
    EXPECT_EQ(lazy.x, full.x) << spec;
    ASSERT_EQ(blocks.size(), s.feats.size() + 2);
    std::vector<int> blockAt(n, -1);
    for (int k = 0; k < static_cast<int>(blocks.size()); ++k) blockAt[blocks[k].off] = k;
    const double tol = 1e-12 * full.P.norm();
    for (int k = 0; k < static_cast<int>(blocks.size()); ++k)
    {
      const auto& bk = blocks[k];
      EXPECT_LT((transitionBlock(lazy.P, bk) - full.P.block(bk.off, bk.off, bk.len, bk.len)).norm(), tol) << spec << k;
      EXPECT_LT((transitionColumns(lazy.P, blocks, k) - full.P.middleCols(bk.off, bk.len)).norm(), tol) << spec << k;
    }
    // H on the features (2 rows each), as the SLAM measurement.
    bayes::CSparseJacobian H(2 * static_cast<int>(s.feats.size()), n);
    for (int k = 0; k < static_cast<int>(s.feats.size()); ++k)
    {
      MatX J(2, s.feats[k].dim());
      for (int c = 0; c < J.size(); ++c) J.data()[c] = g(rng);
      H.addBlock(2 * k, s.feats[k].offset, J);
    }
    const MatX Sref = H.times(H.timesTransposedBy(full.P));
    EXPECT_LT((transitionInnovationCovariance(lazy.P, blocks, blockAt, H) - Sref).norm(), 1e-12 * Sref.norm()) << spec;
    bayes::CSparseJacobian bad(2, n);
    bad.addBlock(0, 0, MatX::Ones(2, 3));  // part of the world pose block
    EXPECT_THROW(transitionInnovationCovariance(lazy.P, blocks, blockAt, bad), std::logic_error);
    applyRobocentricTransition(lazy.P, blocks, scratch);
    EXPECT_LT((lazy.P - full.P).norm(), tol) << spec;
  }
}

TEST(Prediction, FromTheLowerTriangleOnlyIsBitwiseTheSame)
{
  // The IMM's modes are predicted from a mixing that leaves the upper triangle stale
  // (CIMMEstimator::mix with lowerOnly): the prediction must read only what it completes itself.
  const TToyState s = movingToyState();
  std::mt19937 rng(29);
  const int n = static_cast<int>(s.x.size());
  MatX P0 = randomCovariance(n, rng);
  P0.triangularView<Eigen::StrictlyUpper>() = P0.transpose();  // exactly symmetric, as the filter keeps it
  MatX stale = P0;
  stale.triangularView<Eigen::StrictlyUpper>().setConstant(std::numeric_limits<double>::quiet_NaN());
  for (const auto* spec : {"general:1", "rotation:0.5", "stationary"})
    for (const double shake : {0.0, 0.3})
    {
      const auto inc = toyIncrement(s, spec, shake);
      bayes::TGaussian full{s.x, P0}, lower{s.x, stale};
      MatX scratch;
      predictRobocentric(full, s.feats, inc, scratch);
      predictRobocentric(lower, s.feats, inc, scratch, true);
      EXPECT_TRUE(lower.x == full.x) << spec << " shake " << shake;
      EXPECT_TRUE(lower.P == full.P) << spec << " shake " << shake;  // bitwise, and no NaN read
    }
}

TEST(Prediction, StationaryJitterCovariance)
{
  // Stationary with an angular jitter (the shake): P' = P (velocities zeroed) + B N B^T, B = d f(x, n)/dn.
  TToyState s;
  const int n = static_cast<int>(s.x.size());
  MatX P0 = MatX::Identity(n, n) * 0.01;
  TIMMBankOptions b;
  b.models = "stationary";
  b.shake_px = 0.3;
  const auto model = b.parseModels()[0];
  const auto inc = motion::motionIncrement(model, Vec3::Zero(), Vec3::Zero(), 1.0, 200);
  ASSERT_TRUE(inc.identity);
  const auto f = [&](const VecX& nse) -> VecX {
    motion::TMotionIncrement rot;
    rot.dq = math::quatFromRotationVector(nse.tail<3>());
    bayes::TGaussian G{s.x, MatX::Zero(n, n)};
    MatX scratch;
    predictRobocentric(G, s.feats, rot, scratch);
    return G.x;
  };
  const MatX B = math::numericalJacobian(f, VecX::Zero(6), 1e-7);
  MatX Pexp = P0;
  Pexp.middleRows(7, 6).setZero();
  Pexp.middleCols(7, 6).setZero();
  Pexp += B * inc.noiseCov * B.transpose();
  bayes::TGaussian G{s.x, P0};
  MatX scratch;
  predictRobocentric(G, s.feats, inc, scratch);
  EXPECT_LT((G.x.head(7) - s.x.head(7)).norm(), 1e-15);
  EXPECT_LT((G.P - Pexp).norm(), 1e-9);
}

TEST(Prediction, ShakeIsARotationAfterTheMotion)
{
  // A moving model with a shake: the same mean as without it, P' = P'_0 + B N_s B^T with B = d g(s)/ds
  // for g(s) the predicted state re-expressed through a rotation exp(s) of the camera. In the
  // stationary model the shake is the model's angular jitter.
  const TToyState s = movingToyState();
  std::mt19937 rng(23);
  const int n = static_cast<int>(s.x.size());
  const MatX P0 = randomCovariance(n, rng);
  for (const auto* spec : {"general:1", "rotation:0.5"})
  {
    TIMMBankOptions b;
    b.models = spec;
    b.shake_px = 0;
    const auto plain = b.parseModels()[0];
    b.shake_px = 0.3;
    const auto shaken = b.parseModels()[0];
    EXPECT_EQ(shaken.shakePx, 0.3);
    const auto inc0 = motion::motionIncrement(plain, s.x.segment<3>(7), s.x.segment<3>(10), 2.0, 200);
    const auto inc = motion::motionIncrement(shaken, s.x.segment<3>(7), s.x.segment<3>(10), 2.0, 200);
    EXPECT_LT((inc.shakeCov - Mat3::Identity() * (0.3 * 0.3 / (200.0 * 200.0) * 2.0)).norm(), 1e-20) << spec;
    bayes::TGaussian ref{s.x, P0}, G{s.x, P0};
    MatX scratch;
    predictRobocentric(ref, s.feats, inc0, scratch);
    predictRobocentric(G, s.feats, inc, scratch);
    EXPECT_EQ(G.x, ref.x) << spec;
    const auto g = [&](const VecX& sv) -> VecX {
      motion::TMotionIncrement rot;
      rot.dq = math::quatFromRotationVector(sv);
      rot.uNext = ref.x.segment<6>(7);
      bayes::TGaussian R{ref.x, MatX::Zero(n, n)};
      MatX sc;
      predictRobocentric(R, s.feats, rot, sc);
      return R.x;
    };
    const MatX B = math::numericalJacobian(g, VecX::Zero(3), 1e-7);
    const MatX Pexp = ref.P + B * inc.shakeCov * B.transpose();
    EXPECT_LT((G.P - Pexp).norm(), 1e-6 * P0.norm()) << spec;
    EXPECT_LT((G.P - G.P.transpose()).norm(), 1e-15) << spec;
    // The factor the lazy modes use is the same term.
    const MatX F = shakeFactor(ref, s.feats, inc.shakeCov);
    EXPECT_LT((F * F.transpose() - B * inc.shakeCov * B.transpose()).norm(), 1e-6 * P0.norm()) << spec;
  }
  TIMMBankOptions b;
  b.models = "stationary";
  b.shake_px = 0.3;
  const auto inc = motion::motionIncrement(b.parseModels()[0], Vec3::Zero(), Vec3::Zero(), 1.0, 200);
  EXPECT_TRUE(inc.identity);
  EXPECT_NEAR(inc.noiseCov(5, 5), 0.3 * 0.3 / (200.0 * 200.0), 1e-20);
  EXPECT_TRUE(inc.shakeCov.isZero());
}

TEST(StateOps, FeatureInitialisationCovarianceMatchesJacobians)
{
  // Augmenting (x, P) must equal the first-order transfer through y = g(b(uv), rho), anchored at the
  // (exactly known) current camera centre: no cross-covariance with the rest of the state.
  const auto cam = allCameras()[2];
  bayes::TGaussian G{VecX::Zero(13), MatX::Identity(13, 13) * 0.01};
  const Vec2 uv(40, 200);
  TNewRay ray;
  ray.b_C = cam->unproject(uv, &ray.J_b_uv).unitVector();
  ray.rho = 0.7;
  ray.sigmaRho = 0.4;
  ray.sigmaPixel = 1.5;
  bayes::TGaussian out = G;
  appendInverseDepthFeatures(out, {ray});
  VecX in(3);
  in << uv, ray.rho;
  const auto fn = [&](const VecX& v) -> VecX {
    return features::initInverseDepth(Vec3::Zero(), Vec4(1, 0, 0, 0), cam->unproject(v.head<2>()).unitVector(), v[2]);
  };
  const MatX J = math::numericalJacobian(fn, in, 1e-6);
  const Eigen::Vector3d var(1.5 * 1.5, 1.5 * 1.5, 0.4 * 0.4);
  EXPECT_LT((out.x.tail<6>() - fn(in)).norm(), 1e-12);
  EXPECT_LT((out.P.bottomRightCorner(6, 6) - J * var.asDiagonal() * J.transpose()).norm(), 1e-6);
  EXPECT_TRUE(out.P.bottomLeftCorner(6, 13).isZero());
  EXPECT_EQ(out.P.topLeftCorner(13, 13), G.P);
}

TEST(StateOps, ConversionAndDeletionByReparametrization)
{
  std::mt19937 rng(4);
  std::normal_distribution<double> g;
  bayes::TGaussian G;
  const int n = 13 + 6 + 6;
  G.x = VecX::Zero(n);
  G.x.segment<4>(3) << 1, 0, 0, 0;
  G.x.segment<6>(13) << 0.1, 0, 0, 0.2, 0.1, 0.5;
  G.x.segment<6>(19) << 0, 0.1, 0, -0.2, 0.1, 0.8;
  MatX A(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) A(i, j) = g(rng);
  G.P = A * A.transpose();
  // Drop the first feature, convert the second.
  features::Mat36 J;
  TReparamSegment conv{19, 6, false, features::inverseDepthToPoint(G.x.segment<6>(19), &J), J};
  bayes::TGaussian out = G;
  reparametrize(out, {TReparamSegment{0, 13, true, {}, {}}, conv});
  ASSERT_EQ(out.x.size(), 16);
  MatX T = MatX::Zero(16, n);
  T.topLeftCorner(13, 13).setIdentity();
  T.block(13, 19, 3, 6) = J;
  EXPECT_LT((out.P - T * G.P * T.transpose()).norm(), 1e-9);
  EXPECT_EQ(out.P, out.P.transpose());
  EXPECT_LT((out.x.tail<3>() - features::inverseDepthToPoint(G.x.segment<6>(19))).norm(), 1e-15);
}

TEST(StateOps, QuaternionNormalization)
{
  bayes::TGaussian G;
  G.x = VecX::Zero(13);
  G.x.segment<4>(3) << 1.1, 0.1, 0, 0;
  G.P = MatX::Identity(13, 13) * 0.01;
  normalizeQuaternion(G);
  EXPECT_NEAR(G.x.segment<4>(3).norm(), 1.0, 1e-15);
  // The covariance of q is now (nearly) singular along q itself.
  const Vec4 q = G.x.segment<4>(3);
  EXPECT_LT(q.dot(G.P.block<4, 4>(3, 3) * q), 1e-12);
}

namespace
{
/** The camera's motion beyond the filter's model, for the adaptive motion noise: an angular sway of
 * a 10-frame period on every axis with this RMS angular acceleration (px per frame^2), on top of the
 * 0.1 px random walk; and what the filter learned. */
struct TSway
{
  double accelPx = 0;
  bool adaptive = true;      ///< [slam] adaptive_motion_noise
  double* learnedPx = nullptr; ///< the loosest general model's angular noise at the end
  double trueShakePx = 0;      ///< a rotation jitter of the true camera after each frame's motion (px, RMS per axis)
  bool adaptiveShake = true;   ///< [slam] adaptive_shake
  double* learnedShakePx = nullptr; ///< the shake the filter uses at the end
  bool robust = false;         ///< the image path's update (RANSAC, rescue, the adaptive noises) on the given matches
  /** CSlamTracker::setRelativePoseLag; cloneNees gets the NEES of every frame's reported relative pose. */
  int cloneLag = 0;
  std::vector<double>* cloneNees = nullptr;
};

/** One Monte Carlo run of the measurement-level simulation; returns the pose NEES per frame. */
std::vector<double> simulateRun(unsigned seed, int nFrames, const std::string& models, double rhoStd,
                                double* rmsPos = nullptr, double dormantBelow = -1, int* nDormant = nullptr,
                                bool lazy = true, double shakePx = 0, const TSway& sway = TSway())
{
  const auto cam = camera::makeCameraModel("pinhole", 320, 240, {200, 200, 160, 120});
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  std::uniform_real_distribution<double> U(0, 1);
  CMonoSlamIMM::TOptions o;
  o.init_rho = 1.0;
  o.init_rho_std = rhoStd;  // the truth below is drawn from these priors: a Bayesian-consistent set-up
  o.init_linear_velocity_std_px = 1.0;
  o.init_angular_velocity_std_px = 0.5;  // (slow rotation keeps the points in view for 100 frames)
  o.num_threads = 1;
  o.adaptive_pixel_noise = false;  // the simulated noise is known: 1 px
  o.adaptive_motion_noise = sway.adaptive;
  o.adaptive_shake = sway.adaptiveShake;
  o.convert_to_xyz = true;
  TIMMBankOptions b;
  b.models = models;
  if (dormantBelow >= 0) b.dormant_below = dormantBelow;
  b.lazy_prediction = lazy;
  b.shake_px = shakePx;
  CMonoSlamIMM slam(o, b, COnePointRansac::TOptions(), cam);
  slam.setRelativePoseLag(sway.cloneLag);

  const double f = 200, sv = o.init_linear_velocity_std_px / f, sw = o.init_angular_velocity_std_px / f;
  motion::Vec13 xv = motion::Vec13::Zero();
  xv[3] = 1;
  for (int i = 0; i < 3; ++i) xv[7 + i] = sv * g(rng), xv[10 + i] = sw * g(rng);
  // True points: uniform over the first image, inverse depth from the filter's prior.
  std::vector<Vec3> pts;
  std::vector<Vec2> uv0;
  for (int j = 0; j < 40; ++j)
  {
    const Vec2 uv(20 + 280 * U(rng), 20 + 200 * U(rng));
    double rho;
    do rho = o.init_rho + o.init_rho_std * g(rng);
    while (rho < 0.2);
    pts.push_back(cam->unproject(uv).unitVector() / rho);
    uv0.push_back(uv + Vec2(g(rng), g(rng)));
  }
  slam.processMeasurements(0.0, {});
  slam.addFeaturesAt(cv::Mat(), uv0);
  motion::TMotionModel truth{motion::EMotionFamily::General, 0.1, 0.1, ""};
  std::vector<double> nees;
  std::vector<motion::Vec13> history{xv};  // the true camera of every frame
  double se = 0;
  constexpr double kPi = 3.14159265358979323846, kPeriod = 10;
  const double swayAmp = sway.accelPx / f / (std::sqrt(2.0) * std::sin(kPi / kPeriod));  // RMS of its differences
  const auto swayAt = [&](int k, int axis) { return swayAmp * std::sin(2 * kPi * k / kPeriod + 2.1 * axis); };
  for (int k = 1; k <= nFrames; ++k)
  {
    for (int i = 0; i < 3; ++i)
      xv[7 + i] += truth.sigmaLinearPx / f * g(rng),
          xv[10 + i] += truth.sigmaAngularPx / f * g(rng) + swayAt(k, i) - swayAt(k - 1, i);
    xv = motion::predictCamera(truth, xv, 1.0, f);
    if (sway.trueShakePx > 0)
    {
      const Vec3 s(g(rng), g(rng), g(rng));
      xv.segment<4>(3) = math::quatMultiply(xv.segment<4>(3), math::quatFromRotationVector(s * (sway.trueShakePx / f)));
    }
    std::vector<std::pair<std::int64_t, Vec2>> z;
    for (int j = 0; j < 40; ++j)
    {
      Vec2 uv;
      const Vec3 pc = features::xyzInCamera(pts[j], xv.head<3>(), xv.segment<4>(3));
      if (pc.z() > 0.05 && cam->project(pc, uv) && cam->isInImage(uv)) z.emplace_back(j, uv + Vec2(g(rng), g(rng)));
    }
    const auto& rep = slam.processMeasurements(k / 30.0, z, sway.robust);
    if (nDormant) *nDormant += rep.nDormantModes;
    // Pose error [dp; dtheta] with dtheta = 2 vec(q_true^-1 (x) q_est) and its covariance.
    const Vec4 qt = xv.segment<4>(3), qe = slam.cameraOrientation();
    Mat4 Lq;
    Vec4 dq = math::quatMultiply(math::quatConjugate(qt), qe, nullptr, &Lq);
    double sgn = dq[0] < 0 ? -1 : 1;
    Eigen::Matrix<double, 6, 1> e;
    e << slam.cameraPosition() - xv.head<3>(), 2 * sgn * dq.tail<3>();
    Eigen::Matrix<double, 6, 7> Jp = Eigen::Matrix<double, 6, 7>::Zero();
    Jp.topLeftCorner<3, 3>().setIdentity();
    Jp.bottomRightCorner<3, 4>() = 2 * sgn * Lq.bottomRows<3>();
    const MatX Ppose = Jp * slam.cameraPoseCovariance() * Jp.transpose();
    nees.push_back(e.dot(Ppose.ldlt().solve(e)));
    se += e.head<3>().squaredNorm();
    history.push_back(xv);
    if (sway.cloneNees && rep.relFrom >= 0)
    {
      // True T_Cj_Ck (p_Cj = R p_Ck + t) and the error [t - t_hat; Log(R_hat^T R)] of the report's.
      const motion::Vec13& xj = history[static_cast<std::size_t>(rep.relFrom)];
      const Mat3 Rj = math::quatToRotation(xj.segment<4>(3));
      const Vec3 t = Rj.transpose() * (xv.head<3>() - xj.head<3>());
      const Vec4 q = math::quatMultiply(math::quatConjugate(xj.segment<4>(3)), qt);
      Vec4 d = math::quatMultiply(math::quatConjugate(rep.relQ), q);
      if (d[0] < 0) d = -d;
      Vec6 ec;
      ec << t - rep.relT, 2 * d.tail<3>();
      sway.cloneNees->push_back(ec.dot(rep.relCov.ldlt().solve(ec)));
    }
  }
  if (rmsPos) *rmsPos = std::sqrt(se / nFrames);
  if (sway.learnedPx) *sway.learnedPx = slam.filter().loosestAngularNoisePx();
  if (sway.learnedShakePx) *sway.learnedShakePx = slam.filter().shakePx();
  return nees;
}
}  // namespace

namespace
{
/** Average (over runs) pose NEES per frame, and the fraction of frames inside the 95 % band
 * [lo, hi] of that average (also returned, optional). */
double neesInsideFraction(const std::string& models, double rhoStd, double* meanNees, double* bandLo = nullptr,
                          double* bandHi = nullptr)
{
  const int runs = 25, frames = 100, dof = 6;
  std::vector<double> avg(frames, 0.0);
  for (int r = 0; r < runs; ++r)
  {
    const auto n = simulateRun(100 + r, frames, models, rhoStd);
    for (int k = 0; k < frames; ++k) avg[k] += n[k] / runs;
  }
  const double lo = math::chi2Quantile(0.025, runs * dof) / runs, hi = math::chi2Quantile(0.975, runs * dof) / runs;
  int inside = 0;
  for (double a : avg) inside += (a >= lo && a <= hi) ? 1 : 0;
  *meanNees = std::accumulate(avg.begin(), avg.end(), 0.0) / frames;
  if (bandLo) *bandLo = lo;
  if (bandHi) *bandHi = hi;
  std::printf("%s, sigma_rho %.2f: pose NEES band [%.2f, %.2f]; inside on %d %% of frames; mean NEES %.2f\n",
              models.c_str(), rhoStd, lo, hi, inside, *meanNees);
  return static_cast<double>(inside) / frames;
}
}  // namespace

TEST(Consistency, CameraPoseNeesInsideChiSquareBand)
{
  // 25 Monte Carlo runs x 100 frames, 40 points, 1 px noise, truth drawn from the filter's priors and
  // motion model (seeds 100-124). With a depth prior of 5 % the EKF is consistent: the run-averaged
  // NEES is inside the 95 % chi-square band [4.72, 7.43] (6 dof, 25 runs) on >= 80 % of the frames
  // (measured 96 % and 97 %) and its mean over the frames is inside the band from both sides
  // (measured 6.42 and 6.41): an over-confident filter fails the upper edge, an over-cautious one the
  // lower edge.
  double mean = 0, lo = 0, hi = 0;
  EXPECT_GE(neesInsideFraction("general:0.1", 0.05, &mean, &lo, &hi), 0.8);
  EXPECT_GT(mean, lo);
  EXPECT_LT(mean, hi);
  EXPECT_GE(neesInsideFraction("stationary rotation:0.1 general:0.1", 0.05, &mean, &lo, &hi), 0.8);
  EXPECT_GT(mean, lo);
  EXPECT_LT(mean, hi);
  // With the wider depth prior (30 %) the EKF is known to be optimistic (the first-order
  // linearization of the bilinear depth x displacement terms, doc/estimator.md): measured mean NEES
  // 12.13, inside the band on 4 % of the frames, so the chi-square band cannot be asserted here.
  // Asserted from both sides around the measurement instead: 12.13 / 1.2 = 10.1 < mean < 12.13 x 1.2
  // = 14.6 (a covariance grown or shrunk by a 20 % change of the filter fails). A change that makes
  // this case consistent must move it into [lo, hi] and update these bounds to the band's.
  neesInsideFraction("general:0.1", 0.3, &mean, &lo, &hi);
  EXPECT_GT(mean, lo);
  EXPECT_GT(mean, 10.1);
  EXPECT_LT(mean, 14.6);
}

TEST(Consistency, AdaptiveMotionNoiseFollowsACameraThatAcceleratesMoreThanItsModel)
{
  // The camera sways at 2 px per frame^2 (RMS, every axis) while the filter's only model says 1 px:
  // the learned angular noise rises towards the sway (less the half variance it must exceed), and the
  // pose NEES (mean over 10 runs, frames 20-60) comes down towards its 6 dof.
  double learnedAng = 0, neesOn = 0, neesOff = 0;
  const int runs = 10, frames = 60;
  for (int r = 0; r < runs; ++r)
  {
    double learned = 0;
    const auto on = simulateRun(300 + r, frames, "general:1", 0.05, nullptr, -1, nullptr, true, 0,
                                TSway{2.0, true, &learned});
    const auto off = simulateRun(300 + r, frames, "general:1", 0.05, nullptr, -1, nullptr, true, 0, TSway{2.0, false});
    learnedAng += learned / runs;
    neesOn += std::accumulate(on.begin() + 20, on.end(), 0.0) / (frames - 20) / runs;
    neesOff += std::accumulate(off.begin() + 20, off.end(), 0.0) / (frames - 20) / runs;
  }
  std::printf("sway 2 px, model 1 px: learned angular noise %.2f px; pose NEES %.2f (adaptive) / %.2f (fixed)\n",
              learnedAng, neesOn, neesOff);
  EXPECT_GT(learnedAng, 1.4);
  EXPECT_LT(learnedAng, 2.3);
  EXPECT_LT(neesOn, 0.8 * neesOff);
  // Against a 0.5 px model the same sway is held at the bound, 3 times the model's own.
  double bounded = 0;
  simulateRun(300, frames, "general:0.5", 0.05, nullptr, -1, nullptr, true, 0, TSway{2.0, true, &bounded});
  EXPECT_DOUBLE_EQ(bounded, 1.5);
  // Where the camera keeps to its model (0.1 px against 0.5) nothing is learned: the model's own
  // noise, and the same run to the last bit.
  for (unsigned seed : {5u, 6u})
  {
    double learned = 0;
    const auto a = simulateRun(seed, 60, "general:0.5", 0.05, nullptr, -1, nullptr, true, 0, TSway{0, true, &learned});
    const auto b = simulateRun(seed, 60, "general:0.5", 0.05, nullptr, -1, nullptr, true, 0, TSway{0, false});
    EXPECT_EQ(learned, 0.5);
    EXPECT_EQ(a, b);
  }
}

TEST(Consistency, AdaptiveShakeFollowsACameraThatShakesMoreThanItsModel)
{
  // The true camera turns by a random 1 px (RMS per axis) after every frame's motion while the bank
  // allows 0.15 px of shake: the learned shake rises towards it (less the half variance it must
  // exceed) and the pose NEES (mean over 10 runs, frames 20-60) comes down towards its 6 dof.
  double learned = 0, neesOn = 0, neesOff = 0;
  const int runs = 10, frames = 60;
  for (int r = 0; r < runs; ++r)
  {
    double l = 0;
    TSway on{0, true, nullptr, 1.0, true, &l, true}, off{0, true, nullptr, 1.0, false, nullptr, true};
    const auto a = simulateRun(400 + r, frames, "general:0.1", 0.05, nullptr, -1, nullptr, true, 0.15, on);
    const auto b = simulateRun(400 + r, frames, "general:0.1", 0.05, nullptr, -1, nullptr, true, 0.15, off);
    learned += l / runs;
    neesOn += std::accumulate(a.begin() + 20, a.end(), 0.0) / (frames - 20) / runs;
    neesOff += std::accumulate(b.begin() + 20, b.end(), 0.0) / (frames - 20) / runs;
  }
  std::printf("shake 1 px, bank 0.15 px: learned shake %.2f px; pose NEES %.2f (adaptive) / %.2f (fixed)\n", learned,
              neesOn, neesOff);
  EXPECT_GT(learned, 0.6);
  EXPECT_LT(learned, 1.3);
  EXPECT_LT(neesOn, 0.8 * neesOff);
  // A camera that shakes as the bank says: the learned shake scatters about the bank's (it acts only
  // where it exceeds half again its variance, which the scatter sometimes does for a few frames) and
  // the pose NEES is the fixed bank's within 5 %; a bank without shake (shake_px = 0, the paper's
  // models) learns none.
  for (unsigned seed : {5u, 6u})
  {
    double l = 0, none = -1;
    TSway on{0, true, nullptr, 0.15, true, &l, true}, off{0, true, nullptr, 0.15, false, nullptr, true};
    const auto a = simulateRun(seed, 60, "general:0.1", 0.05, nullptr, -1, nullptr, true, 0.15, on);
    const auto b = simulateRun(seed, 60, "general:0.1", 0.05, nullptr, -1, nullptr, true, 0.15, off);
    const double na = std::accumulate(a.begin(), a.end(), 0.0), nb = std::accumulate(b.begin(), b.end(), 0.0);
    std::printf("shake as modelled, seed %u: learned %.3f px; pose NEES %.2f (adaptive) / %.2f (fixed)\n", seed, l,
                na / a.size(), nb / b.size());
    EXPECT_LT(l, 0.2);
    EXPECT_NEAR(na, nb, 0.05 * nb);
    TSway zero{0, true, nullptr, 1.0, true, &none, true};
    simulateRun(seed, 60, "general:0.1", 0.05, nullptr, -1, nullptr, true, 0, zero);
    EXPECT_EQ(none, 0.0);
  }
}

TEST(Consistency, PoseClonesGiveConsistentRelativePoses)
{
  // The camera's motion over the last 10 frames (the tracker's relative pose, from the clone of the
  // frame 10 back in the state) has the filter's covariance: over 25 Monte Carlo runs x 60 frames (the set-up of CameraPoseNeesInsideChiSquareBand),
  // its run-averaged NEES (6 dof) is inside the 95 % band on >= 80 % of the frames, and its mean too,
  // with a single model and with a bank; the clones leave the camera's own estimate as it was.
  for (const char* models : {"general:0.1", "stationary rotation:0.1 general:0.1"})
  {
    const int runs = 25, frames = 60, lag = 10, dof = 6;
    std::vector<double> avg;
    for (int r = 0; r < runs; ++r)
    {
      std::vector<double> cn;
      TSway sw;
      sw.cloneLag = lag;
      sw.cloneNees = &cn;
      const auto withClones = simulateRun(100 + r, frames, models, 0.05, nullptr, -1, nullptr, true, 0, sw);
      if (r < 2)
      {
        const auto without = simulateRun(100 + r, frames, models, 0.05);
        for (std::size_t k = 0; k < without.size(); ++k) EXPECT_NEAR(withClones[k], without[k], 1e-6 * without[k]);
      }
      ASSERT_EQ(cn.size(), static_cast<std::size_t>(frames - lag + 1));
      avg.resize(cn.size(), 0.0);
      for (std::size_t k = 0; k < cn.size(); ++k) avg[k] += cn[k] / runs;
    }
    const double lo = math::chi2Quantile(0.025, runs * dof) / runs, hi = math::chi2Quantile(0.975, runs * dof) / runs;
    int inside = 0;
    for (double a : avg) inside += (a >= lo && a <= hi) ? 1 : 0;
    const double mean = std::accumulate(avg.begin(), avg.end(), 0.0) / static_cast<double>(avg.size());
    std::printf("%s: relative pose (lag %d) NEES band [%.2f, %.2f]; inside on %d of %zu frames; mean %.2f\n", models,
                lag, lo, hi, inside, avg.size(), mean);
    EXPECT_GE(inside, static_cast<int>(0.8 * static_cast<double>(avg.size())));
    EXPECT_GT(mean, lo);
    EXPECT_LT(mean, hi);
  }
}

TEST(IMMSlam, IdenticalModelsGiveTheSingleFilter)
{
  double rms1 = 0, rms3 = 0;
  const auto a = simulateRun(7, 30, "general:0.1", 0.3, &rms1);
  const auto b = simulateRun(7, 30, "general:0.1 general:0.1 general:0.1", 0.3, &rms3);
  for (std::size_t k = 0; k < a.size(); ++k) EXPECT_NEAR(a[k], b[k], 1e-5 * (1 + a[k]));
  EXPECT_NEAR(rms1, rms3, 1e-8);
}

TEST(IMMSlam, DormantModesKeepTheExactBanksEstimate)
{
  // The paper's 7-model bank on general motion: the stationary and rotation modes fall to the floor
  // and are not updated (dormant_below = 1e-5); the estimate stays the exact IMM's within a few % of
  // its error, and a general mode is always updated (the family rule).
  const std::string bank = "stationary rotation:0.1 rotation:0.5 rotation:1 general:0.1 general:0.5 general:1";
  double rmsExact = 0, rmsDormant = 0;
  int dormantExact = 0, dormant = 0;
  const auto a = simulateRun(11, 60, bank, 0.05, &rmsExact, 0.0, &dormantExact);
  const auto b = simulateRun(11, 60, bank, 0.05, &rmsDormant, 1e-5, &dormant);
  EXPECT_EQ(dormantExact, 0);
  EXPECT_GT(dormant, 60 * 2);  // more than 2 of the 7 modes dormant on average
  EXPECT_LE(dormant, 60 * 6);
  EXPECT_NEAR(rmsDormant, rmsExact, 0.1 * rmsExact);
  double na = 0, nb = 0;
  for (std::size_t k = 0; k < a.size(); ++k) na += a[k], nb += b[k];
  EXPECT_NEAR(nb, na, 0.2 * na);
  // Lazy prediction is exact: the same run without it gives the same numbers (up to rounding).
  double rmsEager = 0;
  int dormantEager = 0;
  const auto c = simulateRun(11, 60, bank, 0.05, &rmsEager, 1e-5, &dormantEager, false);
  EXPECT_EQ(dormantEager, dormant);
  EXPECT_NEAR(rmsEager, rmsDormant, 1e-9 * rmsDormant);
  for (std::size_t k = 0; k < a.size(); ++k) EXPECT_NEAR(c[k], b[k], 1e-6 * (1 + b[k]));
  std::printf("7-model bank, 60 frames: %.2f dormant modes per frame, position RMS %.5f (exact %.5f), "
              "mean pose NEES %.2f (exact %.2f)\n",
              dormant / 60.0, rmsDormant, rmsExact, nb / a.size(), na / a.size());
}

TEST(IMMSlam, LazyPredictionIsExactWithAShake)
{
  // The lazy modes add the shake's factor to every block, column and innovation covariance they give
  // out (and to P when they are materialized): the same run as the eager prediction.
  const std::string bank = "stationary rotation:0.1 rotation:0.5 rotation:1 general:0.1 general:0.5 general:1";
  double rmsLazy = 0, rmsEager = 0;
  int dLazy = 0, dEager = 0;
  const auto a = simulateRun(11, 60, bank, 0.05, &rmsLazy, 1e-5, &dLazy, true, 0.15);
  const auto b = simulateRun(11, 60, bank, 0.05, &rmsEager, 1e-5, &dEager, false, 0.15);
  EXPECT_GT(dLazy, 60);
  EXPECT_EQ(dLazy, dEager);
  EXPECT_NEAR(rmsLazy, rmsEager, 1e-9 * rmsEager);
  for (std::size_t k = 0; k < a.size(); ++k) EXPECT_NEAR(a[k], b[k], 1e-6 * (1 + b[k]));
}

TEST(IMMSlam, DefaultMatrixForbidsSwitchesIntoTheGeneralModesOnly)
{
  // A still or rotating mode (v = 0) never switches into a general one (whose velocity the mixing would
  // drag towards 0); every other off-diagonal entry is (1 - transition_stay) / (r - 1).
  TIMMBankOptions b;
  b.models = "stationary rotation:0.1 rotation:0.5 rotation:1 general:0.1 general:0.5 general:1";
  b.transition_stay = 0.995;
  const MatX pi = b.transitionMatrix(7);
  const double even = (1.0 - 0.995) / 6;
  for (int j = 0; j < 7; ++j)
  {
    EXPECT_NEAR(pi.row(j).sum(), 1.0, 1e-15) << "row " << j;
    for (int i = 0; i < 7; ++i)
    {
      EXPECT_GE(pi(j, i), 0.0);
      if (j < 4 && i >= 4)
      {
        EXPECT_EQ(pi(j, i), 0.0) << j << " -> " << i;
      }
      else if (i != j)
      {
        EXPECT_NEAR(pi(j, i), even, 1e-18) << j << " -> " << i;
      }
    }
  }
  EXPECT_NEAR(pi(0, 0), 1.0 - 3 * even, 1e-15);
  EXPECT_NEAR(pi(4, 4), 0.995, 1e-15);
  // An explicit transition_matrix is used as given.
  b.transition_matrix.assign(49, 0.0);
  for (int i = 0; i < 7; ++i) b.transition_matrix[i * 8] = 1.0;
  EXPECT_TRUE(b.transitionMatrix(7) == MatX::Identity(7, 7));
}

TEST(IMMSlam, DroppedFramesGiveTheModesTheTimeToSwitch)
{
  // Frames at 30 Hz with two dropped after the third: that frame is 3 frame periods after the last
  // one, and the bank's mixing uses pi^3 (a mode switch is as likely as over 3 frames).
  const auto cam = camera::makeCameraModel("pinhole", 320, 240, {200, 200, 160, 120});
  CMonoSlamIMM::TOptions o;
  o.num_threads = 1;
  TIMMBankOptions b;
  b.models = "stationary rotation:0.5 general:0.5";
  b.transition_stay = 0.9;
  CMonoSlamIMM slam(o, b, COnePointRansac::TOptions(), cam);
  const MatX pi = b.transitionMatrix(3);
  for (int k : {0, 1, 2, 5, 6})
  {
    const auto& rep = slam.processMeasurements(k / 30.0, {});
    if (k == 0) continue;
    const double steps = k == 5 ? 3.0 : 1.0;
    EXPECT_DOUBLE_EQ(rep.dtFrames, steps) << "frame " << k;
    EXPECT_LE((slam.bank().lastTransition() - slam.bank().transitionOver(steps)).cwiseAbs().maxCoeff(), 1e-15);
    if (k == 5)
    {
      EXPECT_LE((slam.bank().lastTransition() - pi * pi * pi).cwiseAbs().maxCoeff(), 1e-15);
    }
  }
}

TEST(IMMSlam, ATimestampThatGoesBackCountsAsOneFrameAndDoesNotMoveTheClockBack)
{
  // Frames 0, 1, 2, then a stamp at frame 0.5 (going back) and frame 3: the bad one is one frame, and
  // frame 3 is one period after frame 2 (not 2.5 periods after the bad stamp). The same for NaN.
  const auto cam = camera::makeCameraModel("pinhole", 320, 240, {200, 200, 160, 120});
  CMonoSlamIMM::TOptions o;
  o.num_threads = 1;
  CMonoSlamIMM slam(o, TIMMBankOptions(), COnePointRansac::TOptions(), cam);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<std::pair<double, double>> frames = {{0, 0}, {1, 1}, {2, 1}, {0.5, 1}, {3, 1}, {nan, 1}, {4, 1}};
  for (const auto& [k, steps] : frames)
  {
    const auto& rep = slam.processMeasurements(k / 30.0, {});
    if (k == 0) continue;
    EXPECT_DOUBLE_EQ(rep.dtFrames, steps) << "frame at " << k;
  }
}

// ---- Relocalisation: the filter's pose correction (applyPoseCorrection; the relocaliser's image
// tests are in libs/tracking/tests/tracker_image_unittest.cpp) ----

TEST(Relocalisation, PoseCorrectionKeepsTheWorldAndMatchesNumericalJacobians)
{
  const TToyState s = movingToyState();
  std::mt19937 rng(21);
  const int n = static_cast<int>(s.x.size());
  const MatX P0 = randomCovariance(n, rng);
  const Vec3 rNew = s.x.segment<3>(0) + Vec3(0.1, -0.05, 0.2);
  const Vec4 qNew = math::quatMultiply(math::quatFromRotationVector(Vec3(0.05, 0.1, -0.02)), s.x.segment<4>(3));
  const double sT = 0.03, sTh = 0.01;
  Mat6 V = Mat6::Identity() * 4e-4;
  // The correction is a rigid motion of the camera by the increment T_CC' of the estimate (held
  // fixed: the state's uncertainty relative to the camera is carried over, as by a prediction step)
  // plus the pose error e = (e_t, e_theta) of C': t + e_t and dq (x) exp(e_theta); velocities cleared.
  Vec4 dq0 = math::quatMultiply(s.x.segment<4>(3), math::quatConjugate(qNew));
  dq0.normalize();
  const Vec3 t0 = s.x.segment<3>(0) - math::quatRotate(dq0, rNew);
  const auto g = [&](const VecX& x, const Vec6& e) -> VecX {
    motion::TMotionIncrement inc;
    inc.t = t0 + e.head<3>();
    inc.dq = math::quatMultiply(dq0, math::quatFromRotationVector(e.tail<3>()));
    bayes::TGaussian G{x, MatX::Zero(n, n)};
    G.x.segment<6>(7).setZero();
    MatX scratch;
    predictRobocentric(G, s.feats, inc, scratch);
    return G.x;
  };
  bayes::TGaussian G{s.x, P0};
  MatX scratch;
  const Vec6 vel = (Vec6() << 0.01, -0.02, 0.005, 0.001, 0.002, -0.003).finished();
  applyPoseCorrection(G, s.feats, rNew, qNew, sT, sTh, vel, V, scratch);
  // The mean: the camera is at the new pose, the world did not move.
  EXPECT_LT((G.x.segment<3>(0) - rNew).norm(), 1e-12);
  EXPECT_LT(std::min((G.x.segment<4>(3) - qNew).norm(), (G.x.segment<4>(3) + qNew).norm()), 1e-12);
  const auto toWorld = [](const VecX& x, const Vec3& pC) {
    return Vec3(math::quatToRotation(x.segment<4>(3)).transpose() * (pC - x.segment<3>(0)));
  };
  EXPECT_LT((toWorld(G.x, G.x.segment<3>(19)) - toWorld(s.x, s.x.segment<3>(19))).norm(), 1e-12);
  const auto idWorld = [&](const VecX& x) {
    const VecX y = x.segment<6>(13);
    return toWorld(x, features::inverseDepthToPoint(y));
  };
  EXPECT_LT((idWorld(G.x) - idWorld(s.x)).norm(), 1e-12);
  EXPECT_EQ(G.x.segment<6>(7), vel);
  // The covariance: J_x P0 J_x^T + J_e N J_e^T outside the velocities, V on them.
  const MatX Jx = math::numericalJacobian([&](const VecX& x) { return g(x, Vec6::Zero()); }, s.x, 1e-7);
  const MatX Je = math::numericalJacobian([&](const VecX& e) { return g(s.x, Vec6(e)); }, VecX(Vec6::Zero()), 1e-7);
  Mat6 N = Mat6::Zero();
  N.topLeftCorner<3, 3>() = Mat3::Identity() * sT * sT;
  N.bottomRightCorner<3, 3>() = Mat3::Identity() * sTh * sTh;
  MatX expected = Jx * P0 * Jx.transpose() + Je * N * Je.transpose();
  expected.middleRows<6>(7).setZero();
  expected.middleCols<6>(7).setZero();
  expected.block<6, 6>(7, 7) = V;
  EXPECT_LT((G.P - expected).norm(), 1e-6 * P0.norm()) << "difference\n" << (G.P - expected);
  EXPECT_LT((G.P - G.P.transpose()).norm(), 1e-15);
}
