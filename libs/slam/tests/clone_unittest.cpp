/* Tests of the SLAM filter's pose clones (stochastic cloning, robocentric_prediction.h): the prediction
 * carries a clone as it does the world pose, with the covariance of the numerical transition, and the
 * filter's slots (CImmSlamFilter::clonePose) are born exact, recycled in place and their motion read out
 * (relativePose). */
#include <gtest/gtest.h>
#include <immslam/math/numerical_jacobian.h>
#include <immslam/math/quaternion.h>
#include <immslam/slam/CImmSlamFilter.h>
#include <immslam/slam/robocentric_prediction.h>
#include <immslam/slam/state_ops.h>

#include <algorithm>
#include <random>

#include "slam_test_utils.h"

namespace immslam::slam
{
namespace
{
/** Camera (13), two clones (7 each), one inverse-depth and one XYZ feature. */
struct TClonedState
{
  VecX x;
  std::vector<TFeature> feats;
  TClonedState()
  {
    const int n = poseCloneOffset(2) + 6 + 3;
    x = VecX::Zero(n);
    x.segment<3>(0) = Vec3(0.05, -0.02, 0.1);
    x.segment<4>(3) = math::quatFromRotationVector(Vec3(0.02, -0.05, 0.03));
    x.segment<3>(7) << 0.01, -0.02, 0.015;
    x.segment<3>(10) << 0.02, 0.01, -0.03;
    x.segment<3>(poseCloneOffset(0)) = Vec3(-0.04, 0.03, -0.02);
    x.segment<4>(poseCloneOffset(0) + 3) = math::quatFromRotationVector(Vec3(-0.01, 0.04, 0.02));
    x.segment<3>(poseCloneOffset(1)) = Vec3(0.01, 0.02, -0.06);
    x.segment<4>(poseCloneOffset(1) + 3) = math::quatFromRotationVector(Vec3(0.03, 0.01, -0.02));
    const int f0 = poseCloneOffset(2);
    x.segment<6>(f0) << 0.01, 0.02, -0.01, 0.1, -0.05, 0.4;
    x.segment<3>(f0 + 6) << -0.3, 0.2, 2.5;
    TFeature a, b;
    a.offset = f0;
    b.kind = EFeatureKind::XYZ;
    b.offset = f0 + 6;
    feats = {a, b};
  }
};

}  // namespace

TEST(PoseClones, PredictionCarriesEveryCloneAsTheWorldPose)
{
  // Each clone's predicted mean is the world pose's formula applied to it, and the covariance is
  // F (P + E N E^T) F^T + B N_s B^T with F and B numerical (the shake re-expresses the clones too),
  // for a moving model with a shake and for the stationary model's jitter.
  const TClonedState s;
  std::mt19937 rng(31);
  const int n = static_cast<int>(s.x.size());
  const MatX P0 = test::randomCovariance(n, rng);
  for (const auto* spec : {"general:1", "rotation:0.5", "stationary"})
  {
    TIMMBankOptions b;
    b.models = spec;
    b.shake_px = 0.3;
    const auto model = b.parseModels()[0];
    const auto inc = motion::motionIncrement(model, s.x.segment<3>(7), s.x.segment<3>(10), 1.0, 200);
    bayes::TGaussian G{s.x, P0};
    MatX scratch;
    predictRobocentric(G, s.feats, inc, scratch, false, 2);
    for (int c = 0; c < 2; ++c)
    {
      // The same formula on a state whose world pose is the clone (no clones, no features).
      VecX xw = s.x.head(motion::kCamDim);
      xw.head<7>() = s.x.segment<7>(poseCloneOffset(c));
      bayes::TGaussian W{xw, MatX::Zero(motion::kCamDim, motion::kCamDim)};
      predictRobocentric(W, {}, inc, scratch);
      EXPECT_LT((G.x.segment<7>(poseCloneOffset(c)) - W.x.head<7>()).norm(), 1e-15) << spec;
    }
    const auto f = [&](const VecX& x) -> VecX {
      bayes::TGaussian H{x, MatX::Zero(n, n)};
      MatX sc;
      auto i2 = inc;
      i2.shakeCov.setZero();
      if (!inc.identity)
        i2 = motion::motionIncrement(model, x.segment<3>(7), x.segment<3>(10), 1.0, 200), i2.shakeCov.setZero();
      predictRobocentric(H, s.feats, i2, sc, false, 2);
      return H.x;
    };
    const MatX F = math::numericalJacobian(f, s.x, 1e-7);
    MatX Pexp;
    if (inc.identity)
    {
      // Stationary: the velocities are zeroed, the jitter re-expresses the poses and the features.
      const auto jit = [&](const VecX& nv) -> VecX {
        motion::TMotionIncrement rot;
        rot.t = inc.J_t_n * nv;
        rot.dq = math::quatNormalized(Vec4(1, 0, 0, 0) + inc.J_dq_n * nv);
        rot.uNext.setZero();
        bayes::TGaussian R{s.x, MatX::Zero(n, n)};
        R.x.segment<6>(7).setZero();
        MatX sc;
        predictRobocentric(R, s.feats, rot, sc, false, 2);
        return R.x;
      };
      const MatX B = math::numericalJacobian(jit, VecX::Zero(6), 1e-7);
      MatX Pz = P0;
      Pz.middleRows<6>(7).setZero();
      Pz.middleCols<6>(7).setZero();
      Pexp = Pz + B * inc.noiseCov * B.transpose();
    }
    else
    {
      MatX Pt = P0;
      Pt.block<6, 6>(7, 7) += inc.noiseCov;
      VecX xs = s.x;
      bayes::TGaussian M{xs, MatX::Zero(n, n)};
      MatX sc;
      auto i0 = inc;
      i0.shakeCov.setZero();
      predictRobocentric(M, s.feats, i0, sc, false, 2);
      const auto g = [&](const VecX& sv) -> VecX {
        motion::TMotionIncrement rot;
        rot.dq = math::quatFromRotationVector(sv);
        rot.uNext = M.x.segment<6>(7);
        bayes::TGaussian R{M.x, MatX::Zero(n, n)};
        MatX sc2;
        predictRobocentric(R, s.feats, rot, sc2, false, 2);
        return R.x;
      };
      const MatX B = math::numericalJacobian(g, VecX::Zero(3), 1e-7);
      Pexp = F * Pt * F.transpose() + B * inc.shakeCov * B.transpose();
    }
    EXPECT_LT((G.P - Pexp).norm(), 1e-6 * P0.norm()) << spec;
    EXPECT_LT((G.P - G.P.transpose()).norm(), 1e-15) << spec;
  }
}

TEST(PoseClones, InversionMatchesNumericalJacobians)
{
  // T_Cj_C = (T_C_Cj)^-1 of a clone (r, q) with a covariance in the state's (r, q): the covariance of
  // the inverse's [dt; dtheta] is J P J^T with J the numerical Jacobian w.r.t. (r, q) (q not unit).
  std::mt19937 rng(37);
  std::normal_distribution<double> g;
  for (int trial = 0; trial < 10; ++trial)
  {
    const Vec3 r(g(rng), g(rng), g(rng));
    const Vec4 q = 1.3 * math::quatFromRotationVector(Vec3(0.5 * g(rng), 0.5 * g(rng), 0.5 * g(rng)));
    const MatX P = test::randomCovariance(7, rng);
    Vec3 t;
    Vec4 qi;
    Mat6 cov;
    invertPoseClone(r, q, P, t, qi, cov);
    const auto inv = [&](const VecX& x) -> VecX {
      const Vec4 qp = x.tail<4>().normalized();
      const Vec3 ti = -(math::quatToRotation(qp).transpose() * x.head<3>());
      VecX e(6);
      e << ti - t, math::quatToRotationVector(math::quatMultiply(math::quatConjugate(qi), math::quatConjugate(qp)));
      return e;
    };
    VecX x0(7);
    x0 << r, q;
    EXPECT_LT(inv(x0).norm(), 1e-12);
    const MatX J = math::numericalJacobian(inv, x0, 1e-7);
    const MatX expected = J * P * J.transpose();
    EXPECT_LT((cov - expected).norm(), 1e-6 * expected.norm()) << "trial " << trial;
  }
}

TEST(PoseClones, SlotsAreBornExactRecycledInPlaceAndReadInOrder)
{
  const auto cam = camera::makeCameraModel("pinhole", 320, 240, {200, 200, 160, 120});
  CImmSlamFilter::TOptions o;
  o.num_threads = 1;
  TIMMBankOptions b;
  b.models = "stationary general:0.5";
  CImmSlamFilter filter(o, b, cam);
  filter.beginFrame();
  filter.start(0.0);
  filter.addFeatures({CImmSlamFilter::TNewFeature{Vec2(100, 80), 1.0, 1.0, filter.allocateId()},
                      CImmSlamFilter::TNewFeature{Vec2(200, 150), 0.5, 0.3, filter.allocateId()}});
  const VecX before = filter.fusedMean();
  const auto all = [](std::int64_t) { return true; };
  filter.clonePose(all, 2);
  ASSERT_EQ(filter.numClones(), 1);
  EXPECT_EQ(filter.features()[0].offset, poseCloneOffset(1));
  EXPECT_EQ(filter.fusedMean().size(), before.size() + kPoseCloneDim);
  // The features and the camera are unchanged; the clone is the identity with no covariance.
  EXPECT_EQ(filter.fusedMean().head(motion::kCamDim), before.head(motion::kCamDim));
  EXPECT_EQ(filter.fusedMean().tail(12), before.tail(12));
  Vec3 t;
  Vec4 q;
  Mat6 cov;
  ASSERT_EQ(filter.cloneSlots(), std::vector<std::int64_t>{0});
  ASSERT_TRUE(filter.relativePose(0, t, q, cov));
  EXPECT_TRUE(t.isZero());
  EXPECT_EQ(q, Vec4(1, 0, 0, 0));
  EXPECT_TRUE(cov.isZero());
  EXPECT_TRUE(filter.fusedCovarianceBlock(poseCloneOffset(0), kPoseCloneDim).isZero());
  // The frames held, oldest first.
  const auto heldFrames = [&filter] {
    std::vector<std::int64_t> f;
    for (const std::int64_t s : filter.cloneSlots())
      if (s >= 0) f.push_back(s);
    std::sort(f.begin(), f.end());
    return f;
  };
  // Two frames later: a second slot, then the oldest gives way in place (the state does not grow).
  for (int k = 1; k <= 3; ++k)
  {
    filter.beginFrame();
    filter.predict(k / 30.0);
    filter.finishUpdate();
    filter.clonePose(all, 2);
  }
  EXPECT_EQ(filter.numClones(), 2);
  EXPECT_EQ(filter.fusedMean().size(), before.size() + 2 * kPoseCloneDim);
  EXPECT_EQ(heldFrames(), (std::vector<std::int64_t>{2, 3}));
  // The clone of frame 2 has been predicted once: it carries the camera's motion uncertainty.
  ASSERT_TRUE(filter.relativePose(2, t, q, cov));
  EXPECT_GT(cov.trace(), 0.0);
  ASSERT_TRUE(filter.relativePose(3, t, q, cov));
  EXPECT_TRUE(cov.isZero());
  // A clone not kept leaves its slot free and the next clone takes it.
  filter.beginFrame();
  filter.predict(4 / 30.0);
  filter.finishUpdate();
  filter.clonePose([](std::int64_t f) { return f != 2; }, 2);
  EXPECT_EQ(heldFrames(), (std::vector<std::int64_t>{3, 4}));
  EXPECT_EQ(filter.numClones(), 2);
  EXPECT_EQ(filter.features()[0].offset, poseCloneOffset(2));

  // The motion since frame 3 is the inverse of its clone's block of the state, with the covariance of
  // the inversion's numerical Jacobian w.r.t. that block (r, q).
  ASSERT_TRUE(filter.relativePose(3, t, q, cov));
  EXPECT_FALSE(filter.relativePose(2, t, q, cov));
  const auto slot = std::find(filter.cloneSlots().begin(), filter.cloneSlots().end(), 3) - filter.cloneSlots().begin();
  const int off = poseCloneOffset(static_cast<int>(slot));
  const VecX x0 = filter.fusedMean().segment<kPoseCloneDim>(off);
  const auto inv = [&](const VecX& x) -> VecX {
    const Vec4 qp = x.tail<4>().normalized();
    const Vec3 ti = -(math::quatToRotation(qp).transpose() * x.head<3>());
    VecX e(6);
    e << ti - t, math::quatToRotationVector(math::quatMultiply(math::quatConjugate(q), math::quatConjugate(qp)));
    return e;
  };
  EXPECT_LT(inv(x0).norm(), 1e-12);
  const MatX J = math::numericalJacobian(inv, x0, 1e-7);
  const MatX expected = J * filter.fusedCovarianceBlock(off, kPoseCloneDim) * J.transpose();
  EXPECT_LT((cov - expected).norm(), 1e-6 * expected.norm());
}
}  // namespace immslam::slam
