/* Tests: motion models' Jacobians vs numerical, noise Jacobians, what each family keeps fixed. */
#include <gtest/gtest.h>
#include <immslam/math/numerical_jacobian.h>
#include <immslam/math/quaternion.h>
#include <immslam/motion/motion_models.h>

#include <random>

#include "world_motion_model.h"

using namespace immslam;
using namespace immslam::motion;

namespace
{
Vec13 randomCamera(std::mt19937& rng)
{
  std::normal_distribution<double> n(0, 1);
  Vec13 x;
  for (int i = 0; i < 13; ++i) x[i] = n(rng);
  x.segment<4>(kQ).normalize();
  x.segment<3>(kV) *= 0.05;
  x.segment<3>(kW) *= 0.05;
  return x;
}
const TMotionModel kModels[] = {{EMotionFamily::Stationary, 0, 0, ""},
                                {EMotionFamily::Rotation, 0, 0.5, ""},
                                {EMotionFamily::General, 1.0, 0.5, ""}};
}  // namespace

TEST(MotionModels, TransitionJacobians)
{
  std::mt19937 rng(11);
  for (const auto& m : kModels)
    for (double dt : {1.0, 2.5})
      for (int t = 0; t < 10; ++t)
      {
        const Vec13 x = randomCamera(rng);
        Mat13 F;
        predictCamera(m, x, dt, 200.0, &F);
        const MatX Fn = math::numericalJacobian(
            [&](const VecX& v) -> VecX { return predictCamera(m, v, dt, 200.0); }, x);
        EXPECT_LT((Fn - F).norm(), 1e-7) << m.displayName();
      }
}

TEST(MotionModels, NoiseCovarianceMatchesNoiseJacobian)
{
  // Q = G diag(...) G^T with G = df/d(V, W): check G numerically by perturbing the velocities
  // *inside* the motion (x + impulse) — f(x, n) = f(x with v += V, w += W).
  std::mt19937 rng(12);
  const double f = 195.0, dt = 1.0;
  for (const auto& m : kModels)
  {
    const Vec13 x = randomCamera(rng);
    Mat13 Q;
    predictCamera(m, x, dt, f, nullptr, &Q);
    const MatX G = math::numericalJacobian(
        [&](const VecX& n) -> VecX {
          Vec13 xi = x;
          xi.segment<3>(kV) += n.head<3>();
          xi.segment<3>(kW) += n.tail<3>();
          return predictCamera(m, xi, dt, f);
        },
        VecX::Zero(6));
    Eigen::Matrix<double, 6, 1> var;
    const double sa = m.family == EMotionFamily::General ? m.sigmaLinearPx / f * dt : 0;
    const double sw = m.sigmaAngularPx / f * dt;
    var << sa * sa, sa * sa, sa * sa, sw * sw, sw * sw, sw * sw;
    const MatX Qn = G * var.asDiagonal() * G.transpose();
    EXPECT_LT((Qn - Q).norm(), 1e-12) << m.displayName();
    EXPECT_LT((Q - Q.transpose()).norm(), 1e-18);
  }
}

TEST(MotionModels, WhatEachFamilyKeepsFixed)
{
  std::mt19937 rng(13);
  const Vec13 x = randomCamera(rng);
  const Vec13 s = predictCamera(kModels[0], x, 1.0, 200);
  EXPECT_EQ(s.head<7>(), x.head<7>());
  EXPECT_TRUE(s.tail<6>().isZero());
  const Vec13 r = predictCamera(kModels[1], x, 1.0, 200);
  EXPECT_EQ(r.head<3>(), x.head<3>());
  EXPECT_TRUE(r.segment<3>(kV).isZero());
  EXPECT_EQ(r.segment<3>(kW), x.segment<3>(kW));
  // The rotation applied is exp(w dt) in the camera frame.
  const Vec4 qexp = math::quatMultiply(x.segment<4>(kQ), math::quatFromRotationVector(x.segment<3>(kW)));
  EXPECT_LT((r.segment<4>(kQ) - qexp).norm(), 1e-12);
  const Vec13 g = predictCamera(kModels[2], x, 2.0, 200);
  EXPECT_LT((g.head<3>() - (x.head<3>() + 2.0 * x.segment<3>(kV))).norm(), 1e-15);
  EXPECT_NEAR(g.segment<4>(kQ).norm(), 1.0, 1e-15);
}

TEST(MotionModels, Names)
{
  EXPECT_EQ(kModels[0].displayName(), "stationary");
  EXPECT_EQ(kModels[1].displayName(), "rotation_0.5px");
  EXPECT_EQ((TMotionModel{EMotionFamily::General, 1, 1, ""}.displayName()), "general_1px");
  EXPECT_EQ(familyFromName("rotation"), EMotionFamily::Rotation);
  EXPECT_THROW(familyFromName("spinning"), std::invalid_argument);
}

TEST(MotionIncrement, JacobiansAndAgreementWithWorldModel)
{
  std::mt19937 rng(21);
  for (const auto& m : kModels)
    for (int t = 0; t < 10; ++t)
    {
      const Vec13 x = randomCamera(rng);
      const Vec3 v = x.segment<3>(kV), w = x.segment<3>(kW);
      const double dt = 1.5;
      const TMotionIncrement inc = motionIncrement(m, v, w, dt, 200);
      VecX u(6);
      u << v, w;
      const auto fn = [&](const VecX& uu) -> VecX {
        const auto i2 = motionIncrement(m, uu.head<3>(), uu.tail<3>(), dt, 200);
        VecX out(13);
        out << i2.t, i2.dq, i2.uNext;
        return out;
      };
      const MatX Jn = math::numericalJacobian(fn, u);
      if (!inc.identity)
      {
        EXPECT_LT((Jn.topRows(3) - inc.J_t_u).norm(), 1e-8) << m.displayName();
        EXPECT_LT((Jn.middleRows(3, 4) - inc.J_dq_u).norm(), 1e-8) << m.displayName();
        EXPECT_LT((Jn.bottomRows(6) - inc.J_uNext_u).norm(), 1e-8) << m.displayName();
      }
      // Same physical motion as the world-centred model: with v_W = R(q) v_C the new camera pose is
      // r + R(q) t and q (x) dq.
      Vec13 xw = x;
      xw.segment<3>(kV) = math::quatRotate(x.segment<4>(kQ), v);
      const Vec13 xn = predictCamera(m, xw, dt, 200);
      if (m.family == EMotionFamily::General)
      {
        EXPECT_LT((xn.head<3>() - (x.head<3>() + math::quatRotate(x.segment<4>(kQ), inc.t))).norm(), 1e-12);
      }
      EXPECT_LT((xn.segment<4>(kQ) - math::quatMultiply(x.segment<4>(kQ), inc.dq)).norm(), 1e-12);
    }
}
