/* Tests: patchWarp against the exact plane-induced mapping (pinhole and distorted models) and end
 * to end on a rendered plane. */
#include "test_images.h"

#include <gtest/gtest.h>
#include <immslam/camera/CCameraModel.h>
#include <immslam/math/numerical_jacobian.h>
#include <immslam/math/quaternion.h>

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

using namespace immslam;
using namespace immslam::frontend;
using namespace immslam::frontend::test;

// ---------------------------------------------------------------------------------------------
// patchWarp vs the exact plane-induced mapping
// ---------------------------------------------------------------------------------------------

namespace
{
/** The pixel in view k of the point where the ray of pixel u0 (view 0) meets the plane. */
Vec2 exactTransfer(const camera::CCameraModel& cam, const Vec3& r0, const Mat3& R0, const Vec3& rk,
                   const Mat3& Rk, const Vec3& p, const Vec3& n, const Vec2& u0)
{
  const Vec3 d = R0 * cam.unproject(u0).unitVector();
  const double t = n.dot(p - r0) / n.dot(d);
  const Vec3 x = r0 + t * d;
  Vec2 uk;
  cam.project(Rk.transpose() * (x - rk), uk);
  return uk;
}

void checkPatchWarp(const camera::CCameraModel& cam, unsigned seed, int trials)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(-1, 1);
  int tested = 0;
  for (int t = 0; t < trials * 10 && tested < trials; ++t)
  {
    const Vec3 r0(U(rng) * 0.2, U(rng) * 0.2, U(rng) * 0.2);
    const Vec4 q0 = math::quatFromRotationVector(Vec3(U(rng), U(rng), U(rng)) * 0.2);
    const Mat3 R0 = math::quatToRotation(q0);
    // A point in front of camera 0, within the image.
    const Vec2 u0(cam.cx() + U(rng) * 0.35 * cam.width(), cam.cy() + U(rng) * 0.35 * cam.height());
    const double depth = 2 + 3 * (U(rng) + 1) / 2;
    const Vec3 p = r0 + R0 * cam.unproject(u0).unitVector() * depth;
    // Camera k: moved and rotated, looking roughly at p.
    const Vec3 rk = r0 + Vec3(U(rng), U(rng), U(rng)) * 0.8;
    const Vec4 qk =
        math::quatMultiply(q0, math::quatFromRotationVector(Vec3(U(rng), U(rng), U(rng)) * 0.25));
    const Mat3 Rk = math::quatToRotation(qk);
    Vec2 uk;
    if (!cam.project(Rk.transpose() * (p - rk), uk) || !cam.isInImage(uk, 5)) continue;
    // Plane normal: towards camera 0, tilted by up to ~40 deg.
    const Vec3 n = ((r0 - p).normalized() + Vec3(U(rng), U(rng), U(rng)) * 0.4).normalized();
    const Mat2 A = patchWarp(cam, r0, q0, rk, qk, p, n);
    const MatX An =
        math::numericalJacobian([&](const VecX& du) -> VecX
                                { return exactTransfer(cam, r0, R0, rk, Rk, p, n, u0 + Vec2(du)); },
                                VecX(Vec2::Zero()), 1e-4);
    EXPECT_LT((A - An).cwiseAbs().maxCoeff(), 1e-6) << cam.modelName() << " trial " << t << "\nA=\n"
                                                    << A << "\nnumerical=\n"
                                                    << An;
    ++tested;
  }
  EXPECT_EQ(tested, trials) << cam.modelName();
}
}  // namespace

TEST(PatchWarp, MatchesTheNumericalPlaneHomographyPinhole)
{
  checkPatchWarp(*camera::makeCameraModel("pinhole", 320, 240, {200, 210, 161, 118}), 40, 50);
}

TEST(PatchWarp, MatchesTheNumericalPlaneHomographyDistorted)
{
  checkPatchWarp(*camera::makeCameraModel("davison", 320, 240, {195, 195, 162, 125, 9e-6}), 41, 50);
  checkPatchWarp(*camera::makeCameraModel("opencv", 640, 480,
                                          {460, 458, 320, 240, -0.28, 0.07, 2e-4, -1e-4, 0.0}),
                 42, 50);
}

TEST(PatchWarp, SpecialCases)
{
  const auto cam = camera::makeCameraModel("pinhole", 320, 240, {200, 200, 160, 120});
  const Vec4 qI(1, 0, 0, 0);
  const Vec3 p(0, 0, 4);
  // Same pose: identity.
  EXPECT_LT(
      (patchWarp(*cam, Vec3::Zero(), qI, Vec3::Zero(), qI, p, Vec3(0.3, 0, -1)) - Mat2::Identity())
          .norm(),
      1e-12);
  // Moving towards a fronto-parallel plane on the axis: pure scale 4/2; zero normal = facing cam 0.
  const Mat2 A = patchWarp(*cam, Vec3::Zero(), qI, Vec3(0, 0, 2), qI, p, Vec3::Zero());
  EXPECT_LT((A - 2 * Mat2::Identity()).norm(), 1e-12);
  // Rolling the camera by 90 deg about its axis: a 90 deg rotation of the patch.
  const Vec4 qRoll = math::quatFromRotationVector(Vec3(0, 0, M_PI / 2));
  const Mat2 Ar = patchWarp(*cam, Vec3::Zero(), qI, Vec3::Zero(), qRoll, p, Vec3(0, 0, -1));
  EXPECT_LT((Ar - (Mat2() << 0, 1, -1, 0).finished()).norm(), 1e-12);
  // Behind camera k, or plane edge-on: identity.
  EXPECT_EQ(patchWarp(*cam, Vec3::Zero(), qI, Vec3(0, 0, 6), qI, p, Vec3(0, 0, -1)),
            Mat2::Identity());
  EXPECT_EQ(patchWarp(*cam, Vec3::Zero(), qI, Vec3(1, 0, 0), qI, p, Vec3(1, 0, 0)),
            Mat2::Identity());
}

TEST(PatchWarp, PredictsTheAppearanceInARenderedView)
{
  // Render a textured plane in two views with the exact homography and match with the predicted
  // template: end-to-end check of patchWarp + predictTemplate + searchInEllipse.
  const auto cam = camera::makeCameraModel("pinhole", 320, 240, {250, 250, 160, 120});
  const cv::Mat tex = makeTexture(640, 480, 50, 1.2);
  // Plane z = 3 in W (camera 0 at the origin looking along +z); texture pixel (a, b) lies at
  // X = (a - 320) / 100, Y = (b - 240) / 100.
  const auto render = [&](const Vec3& r, const Mat3& R)
  {
    // Homography from the texture to the image: uv ~ K R^T (X - r).
    Eigen::Matrix3d K;
    K << 250, 0, 160, 0, 250, 120, 0, 0, 1;
    Eigen::Matrix3d T;  // texture pixel -> point on the plane (homogeneous X, Y, 1 with z = 3)
    T << 0.01, 0, -3.2, 0, 0.01, -2.4, 0, 0, 1;
    Eigen::Matrix3d P;  // [X Y 1] -> camera coordinates
    const Mat3 Rt = R.transpose();
    P.col(0) = Rt.col(0);
    P.col(1) = Rt.col(1);
    P.col(2) = Rt * (Vec3(0, 0, 3) - r);
    const Eigen::Matrix3d H = K * P * T;
    cv::Mat Hcv(3, 3, CV_64F);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) Hcv.at<double>(i, j) = H(i, j);
    cv::Mat out;
    cv::warpPerspective(tex, out, Hcv, cv::Size(320, 240), cv::INTER_CUBIC, cv::BORDER_REFLECT);
    return out;
  };
  const Vec4 q0(1, 0, 0, 0);
  const Vec3 r0 = Vec3::Zero();
  const Vec3 rk(0.9, -0.3, 0.8);
  const Vec4 qk = math::quatFromRotationVector(Vec3(0.05, -0.25, 0.5));
  const Mat3 Rk = math::quatToRotation(qk);
  const cv::Mat im0 = render(r0, Mat3::Identity()), imk = render(rk, Rk);
  const auto feats = featurePositions(im0, 30, 51, 40);
  TSearchParams sp;
  int n = 0, ok = 0;
  double sumW = 0, sumP = 0;
  for (const Vec2& u0 : feats)
  {
    const Vec3 p = cam->unproject(u0).unitVector() * (3.0 / cam->unproject(u0).unitVector().z());
    Vec2 uk;
    if (!cam->project(Rk.transpose() * (p - rk), uk) || !cam->isInImage(uk, 30)) continue;
    CFeaturePatch patch;
    ASSERT_TRUE(patch.extract(im0, u0, 5));
    const Mat2 A = patchWarp(*cam, r0, q0, rk, qk, p, r0 - p);
    const Mat2 S = Mat2::Identity() * 9;
    const auto rw = searchInEllipse(imk, patch.predictTemplate(A), uk + Vec2(1, 1), S, sp);
    const auto rp = searchInEllipse(imk, patch.originalTemplate(), uk + Vec2(1, 1), S, sp);
    ++n;
    ok += rw.found && (rw.uv - uk).norm() < 0.3;
    sumW += rw.score;
    sumP += rp.score;
  }
  std::printf(
      "[ measure  ] rendered plane: %d features, %d matched within 0.3 px with the warped "
      "template; mean ZNCC warped %.3f, unwarped %.3f\n",
      n, ok, sumW / std::max(n, 1), sumP / std::max(n, 1));
  ASSERT_GT(n, 10);
  EXPECT_GE(ok, n - 1);
}
