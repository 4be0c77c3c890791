/* Tests: inverse-depth / XYZ feature Jacobians against numerical ones, and round trips. */
#include <gtest/gtest.h>
#include <immslam/features/inverse_depth.h>
#include <immslam/math/numerical_jacobian.h>
#include <immslam/math/quaternion.h>

#include <random>

using namespace immslam;
using namespace immslam::features;

namespace
{
struct Rand
{
  std::mt19937 rng{7};
  std::normal_distribution<double> n{0, 1};
  Vec3 vec3(double s = 1) { return Vec3(n(rng), n(rng), n(rng)) * s; }
  Vec4 quat() { return Vec4(n(rng), n(rng), n(rng), n(rng)).normalized(); }
  Vec6 idFeature()
  {
    Vec6 y;
    y << vec3(), 0.8 * n(rng), 0.4 * n(rng), 0.2 + std::abs(n(rng));
    return y;
  }
};
}  // namespace

TEST(InverseDepth, PointJacobian)
{
  Rand R;
  for (int t = 0; t < 30; ++t)
  {
    const Vec6 y = R.idFeature();
    Mat36 J;
    inverseDepthToPoint(y, &J);
    const MatX Jn = math::numericalJacobian([](const VecX& v) -> VecX { return inverseDepthToPoint(v); }, y);
    EXPECT_LT((Jn - J).norm(), 1e-6 * (1 + J.norm()));
  }
}

TEST(InverseDepth, CameraProjectionJacobians)
{
  Rand R;
  for (int t = 0; t < 30; ++t)
  {
    const Vec6 y = R.idFeature();
    const Vec3 r = R.vec3(0.3);
    const Vec4 q = R.quat();
    Mat36 Jy;
    Mat3 Jr;
    Mat34 Jq;
    const Vec3 h = inverseDepthInCamera(y, r, q, &Jy, &Jr, &Jq);
    // h is rho * R_CW (p - r): proportional to the Euclidean point in the camera frame.
    const Vec3 pc = xyzInCamera(inverseDepthToPoint(y), r, q);
    EXPECT_LT((h - y[5] * pc).norm(), 1e-10);
    VecX x(13);
    x << y, r, q;
    const MatX Jn = math::numericalJacobian(
        [](const VecX& v) -> VecX { return inverseDepthInCamera(v.head<6>(), v.segment<3>(6), v.tail<4>()); }, x);
    EXPECT_LT((Jn.leftCols(6) - Jy).norm(), 1e-7);
    EXPECT_LT((Jn.middleCols(6, 3) - Jr).norm(), 1e-7);
    EXPECT_LT((Jn.rightCols(4) - Jq).norm(), 1e-7);
  }
}

TEST(InverseDepth, PointAtInfinityIsWellDefined)
{
  Vec6 y;
  y << 1, 2, 3, 0.3, -0.2, 0.0;
  const Vec3 h = inverseDepthInCamera(y, Vec3(5, 5, 5), Vec4(1, 0, 0, 0));
  EXPECT_LT((h - math::Bearing::DirectionFromAngles(0.3, -0.2)).norm(), 1e-15);
}

TEST(Xyz, CameraJacobians)
{
  Rand R;
  for (int t = 0; t < 30; ++t)
  {
    VecX x(10);
    x << R.vec3(3), R.vec3(0.3), R.quat();
    Mat3 Jp, Jr;
    Mat34 Jq;
    xyzInCamera(x.head<3>(), x.segment<3>(3), x.tail<4>(), &Jp, &Jr, &Jq);
    const MatX Jn = math::numericalJacobian(
        [](const VecX& v) -> VecX { return xyzInCamera(v.head<3>(), v.segment<3>(3), v.tail<4>()); }, x);
    EXPECT_LT((Jn.leftCols(3) - Jp).norm(), 1e-7);
    EXPECT_LT((Jn.middleCols(3, 3) - Jr).norm(), 1e-7);
    EXPECT_LT((Jn.rightCols(4) - Jq).norm(), 1e-7);
  }
}

TEST(InverseDepth, InitJacobiansAndRoundTrip)
{
  Rand R;
  for (int t = 0; t < 30; ++t)
  {
    const Vec3 r = R.vec3(0.5);
    const Vec4 q = R.quat();
    Vec3 b = R.vec3();
    b.z() = 1.0 + std::abs(b.z());
    Mat63 Jr, Jb;
    Mat64 Jq;
    const Vec6 y = initInverseDepth(r, q, b, 1.0, &Jr, &Jq, &Jb);
    // The initialised feature projects back along the observed ray (ID -> camera == ray).
    const Vec3 h = inverseDepthInCamera(y, r, q);
    EXPECT_LT((h.normalized() - b.normalized()).norm(), 1e-12);
    VecX x(10);
    x << r, q, b;
    const MatX Jn = math::numericalJacobian(
        [](const VecX& v) -> VecX { return initInverseDepth(v.head<3>(), v.segment<4>(3), v.tail<3>(), 1.0); }, x);
    EXPECT_LT((Jn.leftCols(3) - Jr).norm(), 1e-7);
    EXPECT_LT((Jn.middleCols(3, 4) - Jq).norm(), 1e-7);
    EXPECT_LT((Jn.rightCols(3) - Jb).norm(), 1e-7);
  }
}

TEST(InverseDepth, IdToXyzToCameraRoundTrip)
{
  Rand R;
  for (int t = 0; t < 20; ++t)
  {
    const Vec6 y = R.idFeature();
    const Vec3 p = inverseDepthToPoint(y);
    // Re-parametrize the same point from another anchor: same Euclidean point.
    const Vec3 r2 = R.vec3(0.2);
    const Vec3 ray = p - r2;
    const Vec2 ang = math::Bearing::AzimuthElevation(ray);
    Vec6 y2;
    y2 << r2, ang, 1.0 / ray.norm();
    EXPECT_LT((inverseDepthToPoint(y2) - p).norm(), 1e-10);
  }
}

TEST(InverseDepth, LinearityIndexFallsWithParallax)
{
  Vec6 y;
  y << 0, 0, 0, 0, 0, 0.5;  // point at depth 2 on the optical axis
  const double sigmaRho = 0.05;
  // Seen from the anchor: no parallax, alpha = 0 -> largest index; seen sideways: smaller.
  const double l0 = linearityIndex(y, sigmaRho, Vec3(0, 0, 0));
  const double l1 = linearityIndex(y, sigmaRho, Vec3(1.5, 0, 0));
  EXPECT_NEAR(l0, 4 * sigmaRho / 0.25 / 2.0, 1e-12);
  EXPECT_LT(l1, l0);
  y[5] = -0.1;
  EXPECT_TRUE(std::isinf(linearityIndex(y, sigmaRho, Vec3::Zero())));
}

TEST(Robocentric, RayAndTransformJacobians)
{
  Rand R;
  for (int t = 0; t < 30; ++t)
  {
    const Vec6 y = R.idFeature();
    Mat36 J;
    inverseDepthRay(y, &J);
    MatX Jn = math::numericalJacobian([](const VecX& v) -> VecX { return inverseDepthRay(v); }, y);
    EXPECT_LT((Jn - J).norm(), 1e-7);
    // Same ray as the world form with the camera at the origin.
    EXPECT_LT((inverseDepthRay(y) - inverseDepthInCamera(y, Vec3::Zero(), Vec4(1, 0, 0, 0))).norm(), 1e-14);

    const Vec4 dq = math::quatFromRotationVector(R.vec3(0.1));
    const Vec3 tr = R.vec3(0.1);
    Mat6 Jy;
    Mat63 Jt;
    Mat64 Jdq;
    const Vec6 y2 = transformInverseDepth(y, dq, tr, &Jy, &Jt, &Jdq);
    // The same Euclidean point, re-expressed: p' = R^T (p - t).
    EXPECT_LT((inverseDepthToPoint(y2) - math::quatToRotation(dq).transpose() * (inverseDepthToPoint(y) - tr)).norm(),
              1e-10);
    VecX x(13);
    x << y, tr, dq;
    Jn = math::numericalJacobian(
        [](const VecX& v) -> VecX { return transformInverseDepth(v.head<6>(), v.tail<4>(), v.segment<3>(6)); }, x);
    EXPECT_LT((Jn.leftCols(6) - Jy).norm(), 1e-7);
    EXPECT_LT((Jn.middleCols(6, 3) - Jt).norm(), 1e-7);
    EXPECT_LT((Jn.rightCols(4) - Jdq).norm(), 1e-7);

    Mat3 Jp, Jt3;
    Mat34 Jdq3;
    const Vec3 p = R.vec3(2);
    transformPoint(p, dq, tr, &Jp, &Jt3, &Jdq3);
    VecX xp(10);
    xp << p, tr, dq;
    Jn = math::numericalJacobian(
        [](const VecX& v) -> VecX { return transformPoint(v.head<3>(), v.tail<4>(), v.segment<3>(3)); }, xp);
    EXPECT_LT((Jn.leftCols(3) - Jp).norm(), 1e-7);
    EXPECT_LT((Jn.middleCols(3, 3) - Jt3).norm(), 1e-7);
    EXPECT_LT((Jn.rightCols(4) - Jdq3).norm(), 1e-7);
  }
}
