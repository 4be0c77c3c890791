/* Tests: the three-ray concurrency test of the shadow filter's classifier (ray_incidence.h) on
 * realistic camera configurations: exact cases, type-I error under H0, power under H1, correlated rays. */
#include <gtest/gtest.h>
#include <immslam/geometry/construction_matrices.h>
#include <immslam/geometry/ray_incidence.h>
#include <immslam/math/chi2.h>
#include <immslam/math/quaternion.h>

#include "geometry_test_utils.h"

using namespace immslam;
using namespace immslam::geometry;
using namespace immslam::geometry::test;

// ---------------------------------------------------------------------------------------------
// 5. Three viewing rays (the classifier's test)
// ---------------------------------------------------------------------------------------------

namespace
{
/** A realistic three-view configuration: a point 1-5 away from the first camera, consecutive camera
 * centres 0.05-0.5 apart in random directions, each camera looking at the point with it up to 23 deg
 * off the optical axis; 1 px pixel noise at f = 200 px, camera centre noise sigma_c in [0, 0.01],
 * orientation noise sigma_theta in [0, 0.002] rad (as a SLAM filter would report). */
struct TRayScenario
{
  Vec3 X;
  Vec3 C[3];
  Mat3 R[3];  ///< R_W_C of each camera
  double sigmaC = 0, sigmaTheta = 0;
  static constexpr double f = 200, sigmaPx = 1;
};

TRayScenario randomRayScenario(Rng& rng)
{
  TRayScenario s;
  s.C[0] = randn(rng, 3);
  s.X = s.C[0] + uniform(rng, 1, 5) * randomUnit(rng);
  s.C[1] = s.C[0] + uniform(rng, 0.05, 0.5) * randomUnit(rng);
  s.C[2] = s.C[1] + uniform(rng, 0.05, 0.5) * randomUnit(rng);
  for (int k = 0; k < 3; ++k)
  {
    const Vec3 toX = (s.X - s.C[k]).normalized();
    const Eigen::AngleAxisd off(uniform(rng, 0, 0.4), randomPerpendicular(rng, toX));
    const Vec3 z = off * toX;
    const Vec3 x = randomPerpendicular(rng, z);
    s.R[k].col(0) = x;
    s.R[k].col(1) = z.cross(x);
    s.R[k].col(2) = z;
  }
  s.sigmaC = uniform(rng, 0, 0.01);
  s.sigmaTheta = uniform(rng, 0, 0.002);
  return s;
}

/** What the classifier would build from camera k observing the world point Xk: noisy pixel, noisy
 * pose estimate, and the viewing ray with covariance evaluated at the estimates. farPoint: build it as
 * the join of the centre with the far point c + 10 d (correlated inputs, eq. (11)) instead of the
 * point at infinity of d. */
TUncertainLine3 observeRay(Rng& rng, const TRayScenario& s, int k, const Vec3& Xk, bool farPoint)
{
  const Vec3 pc = s.R[k].transpose() * (Xk - s.C[k]);
  const double sn = s.sigmaPx / s.f;  // pixel noise in normalized image coordinates
  const Vec3 m(pc.x() / pc.z() + sn * randn(rng, 1)[0], pc.y() / pc.z() + sn * randn(rng, 1)[0], 1.0);
  const Vec3 c = s.C[k] + s.sigmaC * Vec3(randn(rng, 3));
  const Mat3 Rhat = math::quatToRotation(math::quatFromRotationVector(s.sigmaTheta * Vec3(randn(rng, 3)))) * s.R[k];
  const Vec3 d = Rhat * m;
  const Mat3 Sc = s.sigmaC * s.sigmaC * Mat3::Identity();
  const Mat3 Sd = Rhat * Eigen::Vector3d(sn * sn, sn * sn, 0).asDiagonal() * Rhat.transpose() +
                  s.sigmaTheta * s.sigmaTheta * math::skew(d) * math::skew(d).transpose();
  if (!farPoint) return viewingRay(c, Sc, d, Sd);
  const double depth = 10;
  const TUncertainPoint3 C = TUncertainPoint3::FromEuclidean(c, Sc);
  const TUncertainPoint3 P = TUncertainPoint3::FromEuclidean(c + depth * d, Sc + depth * depth * Sd);
  Mat4 cCP = Mat4::Zero();
  cCP.topLeftCorner<3, 3>() = Sc;  // P = c + depth d shares c's error
  return join(C, P, &cCP);
}
}  // namespace

TEST(ThreeRays, ExactRaysMeetAndIntersectionIsThePoint)
{
  Rng rng(12);
  for (int t = 0; t < 50; ++t)
  {
    const TRayScenario s = randomRayScenario(rng);
    const Mat3 S = 1e-6 * Mat3::Identity();
    TUncertainLine3 rays[3];
    for (int k = 0; k < 3; ++k) rays[k] = viewingRay(s.C[k], S, s.X - s.C[k], S);
    const TRayIncidenceTest r = threeRaysMeet(rays[0], rays[1], rays[2], 0.05);
    ASSERT_TRUE(r.test.valid);
    EXPECT_LT(r.test.T, 1e-12);
    EXPECT_TRUE(r.test.accepted);
    EXPECT_EQ(r.test.dof, 3);
    EXPECT_LT((r.intersection.euclidean() - s.X).norm(), 1e-8);
    // Rays 2 and 3 through a point 0.1 away from X: rejected with these tiny covariances.
    const Vec3 off = s.X + 0.1 * randomPerpendicular(rng, s.X - s.C[2]);
    rays[2] = viewingRay(s.C[2], S, off - s.C[2], S);
    EXPECT_TRUE(threeRaysMeet(rays[0], rays[1], rays[2], 0.05).test.rejected());
  }
  // Joint covariance argument: block-diagonal equals the default.
  const TRayScenario s = randomRayScenario(rng);
  TUncertainLine3 rays[3];
  MatX S18 = MatX::Zero(18, 18);
  for (int k = 0; k < 3; ++k)
  {
    rays[k] = observeRay(rng, s, k, s.X, false);
    S18.block<6, 6>(6 * k, 6 * k) = rays[k].cov;
  }
  EXPECT_NEAR(threeRaysMeet(rays[0], rays[1], rays[2], 0.05, &S18).test.T,
              threeRaysMeet(rays[0], rays[1], rays[2], 0.05).test.T, 1e-9);
  const MatX wrongSize = MatX::Zero(6, 6);
  EXPECT_THROW(threeRaysMeet(rays[0], rays[1], rays[2], 0.05, &wrongSize), std::invalid_argument);
}

TEST(ThreeRays, ALevelComputedOnceGivesBitwiseTheSameTest)
{
  // TSignificance holds the critical values the alpha overloads compute on every call (a bisection
  // of the incomplete gamma function): the same numbers, so the same decisions, bitwise.
  for (const double alpha : {0.01, 0.05, 0.2})
  {
    const TSignificance level = TSignificance::At(alpha);
    for (int r = 1; r <= 6; ++r) EXPECT_EQ(level.threshold(r), math::chi2Quantile(1.0 - alpha, r)) << r;
    Rng rng(31);
    for (int t = 0; t < 20; ++t)
    {
      const TRayScenario s = randomRayScenario(rng);
      TUncertainLine3 rays[3];
      for (int k = 0; k < 3; ++k) rays[k] = observeRay(rng, s, k, s.X, t % 2 == 1);
      const TRayIncidenceTest a = threeRaysMeet(rays[0], rays[1], rays[2], alpha);
      const TRayIncidenceTest b = threeRaysMeet(rays[0], rays[1], rays[2], level);
      EXPECT_EQ(a.test.threshold, b.test.threshold);
      EXPECT_EQ(a.coplanar.threshold, b.coplanar.threshold);
      EXPECT_EQ(a.onThirdRay.threshold, b.onThirdRay.threshold);
      EXPECT_EQ(a.test.accepted, b.test.accepted);
      if (a.test.valid) EXPECT_EQ(a.test.T, b.test.T);
    }
  }
  EXPECT_THROW(TSignificance::At(0.0), std::invalid_argument);
  EXPECT_THROW(TSignificance::At(1.0), std::invalid_argument);
}

TEST(ThreeRays, ErrorRates)
{
  Rng rng(13);
  const double alpha = 0.05;
  const int n = 10000;
  // H0: a static point seen from three poses.
  int rej = 0, invalid = 0, rejCop = 0, rejOn = 0, rejFar = 0;
  for (int i = 0; i < n; ++i)
  {
    const TRayScenario s = randomRayScenario(rng);
    const bool far = (i % 2) == 1;
    const TRayIncidenceTest r = threeRaysMeet(observeRay(rng, s, 0, s.X, far), observeRay(rng, s, 1, s.X, far),
                                              observeRay(rng, s, 2, s.X, far), alpha);
    invalid += !r.test.valid;
    rej += r.test.rejected();
    rejFar += far && r.test.rejected();
    rejCop += r.coplanar.rejected();
    rejOn += r.onThirdRay.rejected();
  }
  reportRate("three rays concurrent under H0 (3 dof)", rej, n);
  reportRate("  rays = centre ^ point at infinity", rej - rejFar, n / 2);
  reportRate("  rays = centre ^ far point, correlated (eq. 11)", rejFar, n / 2);
  reportRate("  its 1-dof part (pair coplanar)", rejCop, n);
  reportRate("  its 2-dof part (intersection on third ray)", rejOn, n);
  EXPECT_EQ(invalid, 0);
  EXPECT_NEAR(static_cast<double>(rej) / n, alpha, 0.01);

  // H1: the point moves by 15 px (at the third camera's depth) before the third view, across the plane
  // spanned by the third ray and the second ray's direction (the direction a depth error cannot explain).
  rej = 0;
  int rejRandom = 0;
  for (int i = 0; i < n; ++i)
  {
    const TRayScenario s = randomRayScenario(rng);
    const Vec3 toX3 = s.X - s.C[2];
    const Vec3 across = toX3.cross(s.X - s.C[1]).normalized();
    const double shift = 15.0 / TRayScenario::f * toX3.norm();
    const Vec3 X3 = s.X + shift * across;
    const TRayIncidenceTest r = threeRaysMeet(observeRay(rng, s, 0, s.X, false), observeRay(rng, s, 1, s.X, false),
                                              observeRay(rng, s, 2, X3, false), alpha);
    rej += r.test.rejected();
    // The same shift in a random direction perpendicular to the third ray (reported only: a shift
    // along the epipolar direction is what a depth error explains, undetectable at small parallax).
    const Vec3 X3r = s.X + shift * randomPerpendicular(rng, toX3);
    rejRandom += threeRaysMeet(observeRay(rng, s, 0, s.X, false), observeRay(rng, s, 1, s.X, false),
                               observeRay(rng, s, 2, X3r, false), alpha)
                     .test.rejected();
  }
  reportRate("three rays, point moved 15 px across the epipolar plane before view 3", rej, n);
  reportRate("three rays, point moved 15 px in a random direction before view 3 (info)", rejRandom, n);
  EXPECT_GT(rej, 0.99 * n);
}

TEST(ThreeRays, CorrelatedRaysUseTheJointCovariance)
{
  // The three camera centres share a common error s (sigma 0.02, e.g. the map's drift in a SLAM
  // filter) on top of independent ones. A common shift moves the rays together and cannot break
  // their concurrency: with the joint covariance (cross blocks J_k sigma_s^2 J_l^T) the test keeps its
  // level; treating the rays as independent over-states the uncertainty (conservative).
  Rng rng(14);
  const double alpha = 0.05, sigmaS = 0.02;
  const int n = 4000;
  int rejJoint = 0, rejIndep = 0;
  for (int i = 0; i < n; ++i)
  {
    TRayScenario s = randomRayScenario(rng);
    const Vec3 common = sigmaS * Vec3(randn(rng, 3));
    TUncertainLine3 rays[3];
    Eigen::Matrix<double, 6, 3> J_L_c[3];
    for (int k = 0; k < 3; ++k)
    {
      TRayScenario sk = s;
      sk.C[k] += common;  // the estimate carries the common error ...
      TUncertainLine3 r = observeRay(rng, sk, k, s.X + common, false);  // ... consistently with the point
      // Re-express with the total centre covariance: add sigma_s^2 I through dL/dc = [0; -[d]x].
      J_L_c[k].topRows<3>().setZero();
      J_L_c[k].bottomRows<3>() = -math::skew(r.L.head<3>());
      r.cov += sigmaS * sigmaS * J_L_c[k] * J_L_c[k].transpose();
      rays[k] = r;
    }
    MatX S = MatX::Zero(18, 18);
    for (int k = 0; k < 3; ++k)
      for (int l = 0; l < 3; ++l)
        S.block<6, 6>(6 * k, 6 * l) =
            k == l ? rays[k].cov : Mat6(sigmaS * sigmaS * J_L_c[k] * J_L_c[l].transpose());
    rejJoint += threeRaysMeet(rays[0], rays[1], rays[2], alpha, &S).test.rejected();
    rejIndep += threeRaysMeet(rays[0], rays[1], rays[2], alpha).test.rejected();
  }
  reportRate("three rays, correlated centres, joint covariance", rejJoint, n);
  reportRate("three rays, correlated centres, treated as independent (info)", rejIndep, n);
  EXPECT_NEAR(static_cast<double>(rejJoint) / n, alpha, 0.015);
  EXPECT_LT(rejIndep, rejJoint);
}

