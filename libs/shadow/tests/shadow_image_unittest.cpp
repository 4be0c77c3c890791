/* Tests: the shadow filter on images — a short rendered sequence (a textured background plane and a
 * textured square moving in front of it, seen by a hand-held camera): features are tracked by the
 * filter's own active search and those on the moving square are classified dynamic. Also reports
 * the per-frame cost with 20 and 50 shadow features. */
#include <gtest/gtest.h>
#include <immslam/frontend/frontend.h>
#include <immslam/shadow/CShadowFilter.h>

#include <opencv2/imgproc.hpp>

#include <chrono>
#include <map>

#include "shadow_test_utils.h"

using namespace immslam;
using namespace immslam::shadow;
using namespace immslam::shadow::test;

namespace
{
/** Random texture: smooth noise plus filled discs and polygons, blurred (deterministic). */
cv::Mat makeTexture(int W, int H, unsigned seed, int pxPerBlob, int rMin, int rMax)
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

/** Truth of a feature from its first pixel: 1 on the square's interior, 0 on the background away
 * from the square, -1 near the square's border (corners there mix both: not scored). */
int truthAt(const cv::Mat& onSquare, const Vec2& uv)
{
  const int u = int(std::lround(uv.x())), v = int(std::lround(uv.y()));
  int lo = 255, hi = 0;
  for (int dv = -7; dv <= 7; ++dv)
    for (int du = -7; du <= 7; ++du)
    {
      const int x = std::clamp(u + du, 0, onSquare.cols - 1), y = std::clamp(v + dv, 0, onSquare.rows - 1);
      lo = std::min<int>(lo, onSquare.at<uchar>(y, x));
      hi = std::max<int>(hi, onSquare.at<uchar>(y, x));
    }
  if (lo == 255) return 1;
  if (hi == 0) return 0;
  return -1;
}
}  // namespace

TEST(ShadowImage, TracksAndClassifiesAMovingSquare)
{
  const TScene scene;
  CShadowFilter::TOptions opts;
  CShadowFilter filter(opts, scene.cam);
  frontend::TDetectorParams det;
  det.gridCols = 10;
  det.gridRows = 8;
  std::map<std::int64_t, int> truth;
  std::map<std::int64_t, EShadowClass> decided;
  int searched = 0, measured = 0, timedOut = 0, lost = 0;
  const int nFrames = 240;
  for (int k = 0; k < nFrames; ++k)
  {
    cv::Mat onSquare;
    const cv::Mat grey = scene.render(k, &onSquare);
    const TShadowReport& rep = filter.processFrame(scene.motion(k), grey);
    searched += rep.nSearched;
    measured += rep.nMeasured;
    timedOut += rep.nTimedOut;
    lost += rep.nLost;
    for (const auto& d : rep.decisions) decided[d.id] = d.cls;
    // Keep ~30 features: new corners in cells free of shadow features.
    const int want = 30 - static_cast<int>(filter.size());
    if (want > 0 && k < nFrames - 90)
    {
      std::vector<Vec2> uv;
      for (const auto& c : frontend::detectInEmptyCells(grey, filter.occupiedPixels(), want, det)) uv.push_back(c.uv);
      const auto ids = filter.addFeatures(grey, uv);
      for (size_t i = 0; i < ids.size(); ++i)
        if (ids[i] >= 0) truth[ids[i]] = truthAt(onSquare, uv[i]);
    }
  }
  int sqTotal = 0, sqDynamic = 0, sqStatic = 0, bgTotal = 0, bgStatic = 0, bgDynamic = 0;
  for (const auto& [id, t] : truth)
  {
    const auto it = decided.find(id);
    const EShadowClass c = it == decided.end() ? EShadowClass::Pending : it->second;
    if (t == 1)
    {
      ++sqTotal;
      sqDynamic += c == EShadowClass::Dynamic;
      sqStatic += c == EShadowClass::Static;
    }
    else if (t == 0)
    {
      ++bgTotal;
      bgStatic += c == EShadowClass::Static;
      bgDynamic += c == EShadowClass::Dynamic;
    }
  }
  std::printf("[ shadow   ] image sequence: %d frames, search success %.1f %% (%d searches)\n", nFrames,
              100.0 * measured / std::max(1, searched), searched);
  std::printf("[ shadow   ] pending features timed out %d, lost %d\n", timedOut, lost);
  std::printf("[ shadow   ] features on the moving square: %d, dynamic %d, static %d\n", sqTotal, sqDynamic, sqStatic);
  std::printf("[ shadow   ] features on the background:    %d, static %d, dynamic %d\n", bgTotal, bgStatic, bgDynamic);
  EXPECT_GE(sqTotal, 5);
  EXPECT_EQ(sqStatic, 0);
  EXPECT_GE(sqDynamic, 0.8 * sqTotal);
  EXPECT_GE(bgTotal, 30);
  EXPECT_LE(bgDynamic, 0.1 * bgTotal);
  EXPECT_GE(bgStatic, 0.2 * bgTotal);
  EXPECT_GE(double(measured) / searched, 0.85);
}

TEST(ShadowImage, PerFrameCost)
{
  const TScene scene;
  std::vector<cv::Mat> frames;
  for (int k = 0; k < 60; ++k) frames.push_back(scene.render(k));
  for (int n : {20, 50})
  {
    CShadowFilter::TOptions opts;
    opts.max_pending_frames = 1000;  // keep the features: the cost is measured with n held
    opts.static_min_velocity_px = 1e-6;
    CShadowFilter filter(opts, scene.cam);
    frontend::TDetectorParams det;
    det.gridCols = 10;
    det.gridRows = 8;
    det.minDistancePx = 8;
    double total = 0, held = 0, tPred = 0, tSearch = 0, tUpd = 0, tCls = 0;
    int counted = 0;
    for (int k = 0; k < 60; ++k)
    {
      const auto t0 = std::chrono::steady_clock::now();
      const TShadowReport& rep = filter.processFrame(scene.motion(k), frames[k]);
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      if (k >= 10)
      {
        total += ms;
        held += rep.nPending + rep.nDynamic;
        tPred += rep.tPredictMs;
        tSearch += rep.tSearchMs;
        tUpd += rep.tUpdateMs;
        tCls += rep.tClassifyMs;
        ++counted;
      }
      const int want = n - static_cast<int>(filter.size());
      if (want > 0)
      {
        std::vector<Vec2> uv;
        for (const auto& c : frontend::detectInEmptyCells(frames[k], filter.occupiedPixels(), want, det))
          uv.push_back(c.uv);
        filter.addFeatures(frames[k], uv);
      }
    }
    std::printf("[ shadow   ] per-frame cost with %.1f shadow features (target %d): %.3f ms (320x240, processFrame: "
                "predict %.3f, search %.3f, update %.3f, classify %.3f)\n",
                held / counted, n, total / counted, tPred / counted, tSearch / counted, tUpd / counted, tCls / counted);
  }
}
