/* The rendered scene of the shadow filter's image tests (shadow_image_unittest) and of its per-frame
 * cost benchmark (tests/benchmarks/bench_shadow): a textured background plane and a textured square
 * moving in front of it, seen by a hand-held camera. Deterministic. */
#pragma once

#include <immslam/shadow/CShadowFilter.h>

#include <opencv2/imgproc.hpp>

#include <cmath>

#include "../../shadow/tests/shadow_test_utils.h"

namespace immslam::shadow::test
{
/** Random texture: smooth noise plus filled discs and polygons, blurred (deterministic). */
inline cv::Mat makeTexture(int W, int H, unsigned seed, int pxPerBlob, int rMin, int rMax)
{
  cv::RNG rng(seed);
  cv::Mat lo(H / 16 + 2, W / 16 + 2, CV_32F);
  rng.fill(lo, cv::RNG::NORMAL, 128, 25);
  cv::Mat smooth, img;
  cv::resize(lo, smooth, cv::Size(W, H), 0, 0, cv::INTER_CUBIC);
  smooth.convertTo(img, CV_8U);
  const int n = W * H / pxPerBlob;
  for (int i = 0; i < n; ++i)
  {
    const cv::Point c(rng.uniform(0, W), rng.uniform(0, H));
    const cv::Scalar col(rng.uniform(0, 256));
    const int r = rng.uniform(rMin, rMax);
    if (rng.uniform(0, 2) == 0)
      cv::circle(img, c, r, col, cv::FILLED, cv::LINE_AA);
    else
    {
      std::vector<cv::Point> poly;
      for (int k = 0; k < 4; ++k)
      {
        const double a = k * CV_PI / 2 + rng.uniform(-0.6, 0.6);
        poly.emplace_back(c.x + int(r * std::cos(a)), c.y + int(r * std::sin(a)));
      }
      cv::fillConvexPoly(img, poly, col, cv::LINE_AA);
    }
  }
  cv::GaussianBlur(img, img, cv::Size(0, 0), 1.0);
  return img;
}

/** A textured planar rectangle in W: points O + a e1 + b e2, texture pixel (i, j) at
 * (a, b) = (i, j) / pxPerUnit (pixel centres at integers). */
struct TPlane
{
  cv::Mat texture;
  Vec3 O = Vec3::Zero(), e1 = Vec3::UnitX(), e2 = Vec3::UnitY();
  double pxPerUnit = 200;

  /** Homography texture -> image for the camera pose. */
  cv::Mat homography(const camera::CCameraModel& cam, const TPose& pose) const
  {
    Mat3 K;
    K << cam.fx(), 0, cam.cx(), 0, cam.fy(), cam.cy(), 0, 0, 1;
    Mat3 B;
    B.col(0) = e1 / pxPerUnit;
    B.col(1) = e2 / pxPerUnit;
    B.col(2) = O - pose.r;
    const Mat3 H = K * pose.R().transpose() * B;
    cv::Mat h(3, 3, CV_64F);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) h.at<double>(r, c) = H(r, c);
    return h;
  }
};

/** The scene: a background plane 4 units ahead and a 0.6 x 0.6 square 2 units ahead moving at
 * constant velocity. */
struct TScene
{
  camera::CCameraModel::Ptr cam = simCamera();
  TPlane background, square;
  Vec3 squareVel = Vec3::Zero();  ///< length per frame
  THandheldPath path;

  TScene()
  {
    // Background: 12 x 9 units at 100 px per unit (~4 texture px per image px at 4 units).
    background.texture = makeTexture(1200, 900, 7, 600, 6, 20);
    background.pxPerUnit = 100;
    background.O = Vec3(-6, -4.5, 3.5);
    // Square: 0.6 units at 400 px per unit (~4 texture px per image px at 2 units).
    square.texture = makeTexture(400, 400, 11, 900, 10, 28);
    square.pxPerUnit = 400;
    square.O = Vec3(-0.6, -0.3, 2);
    squareVel = Vec3(0.45, 0.12, 0.0) / 30;
    Rng rng(5);
    path = randomHandheldPath(rng, 0.35 / 30);
  }

  TPose pose(int k) const { return TPose{path.position(k), path.orientation(k)}; }

  /** Renders frame k; `onSquare` (CV_8U) marks the square's pixels. */
  cv::Mat render(int k, cv::Mat* onSquare = nullptr) const
  {
    const TPose P = pose(k);
    const cv::Size sz(cam->width(), cam->height());
    cv::Mat img, sq, mask;
    cv::warpPerspective(background.texture, img, background.homography(*cam, P), sz, cv::INTER_LINEAR,
                        cv::BORDER_REPLICATE);
    TPlane s = square;
    s.O += squareVel * k;
    const cv::Mat H = s.homography(*cam, P);
    cv::warpPerspective(s.texture, sq, H, sz, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
    cv::warpPerspective(cv::Mat(s.texture.size(), CV_8U, cv::Scalar(255)), mask, H, sz, cv::INTER_LINEAR,
                        cv::BORDER_CONSTANT);
    // Anti-aliased composition.
    cv::Mat imgF, sqF, a;
    img.convertTo(imgF, CV_32F);
    sq.convertTo(sqF, CV_32F);
    mask.convertTo(a, CV_32F, 1.0 / 255);
    cv::Mat out = imgF.mul(1 - a) + sqF.mul(a);
    cv::Mat noise(sz, CV_32F);
    cv::RNG rng(1000 + k);
    rng.fill(noise, cv::RNG::NORMAL, 0, 1.5);
    out += noise;
    out.convertTo(img, CV_8U);
    if (onSquare) *onSquare = mask;
    return img;
  }

  TCameraMotion motion(int k) const
  {
    const TPose a = pose(k > 0 ? k - 1 : 0), b = pose(k);
    TCameraMotion m = TCameraMotion::FromPoses(a.r, a.q, b.r, b.q);
    m.frame = k;
    m.timestamp = k / 30.0;
    m.cov_increment.diagonal() << Vec3::Constant(1e-8), Vec3::Constant(1e-8);
    m.cov_W_C.diagonal() << Vec3::Constant(1e-6), Vec3::Constant(1e-6);
    return m;
  }
};
}  // namespace immslam::shadow::test
