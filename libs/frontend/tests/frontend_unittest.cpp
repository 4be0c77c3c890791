/* Tests: corner detection, patch prediction (warping) and active search in the gate ellipse, on
 * synthetic images generated here. Measurements are printed ("[ measure  ]"), never asserted. */
#include "test_images.h"

#include <gtest/gtest.h>
#include <immslam/camera/CFisheyeCamera.h>
#include <immslam/camera/COpenCVCamera.h>
#include <immslam/camera/CPinholeCamera.h>

#include <Eigen/Cholesky>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

using namespace immslam;
using namespace immslam::frontend;
using namespace immslam::frontend::test;

// ---------------------------------------------------------------------------------------------
// Detection
// ---------------------------------------------------------------------------------------------

TEST(Detection, CornersOnlyInEmptyCellsFarFromOccupiedWithinBorders)
{
  const cv::Mat img = makeTexture(320, 240, 1);
  TDetectorParams p;
  const std::vector<Vec2> occupied = {{20, 20},  {100, 50},  {170.5, 90.2}, {250, 130},
                                      {60, 200}, {300, 220}, {-5, 10} /* outside: ignored */};
  const int maxNew = 20;
  const auto corners = detectInEmptyCells(img, occupied, maxNew, p);
  ASSERT_GT(corners.size(), 10u);
  EXPECT_LE(int(corners.size()), maxNew);
  const auto cellOf = [&](const Vec2& uv)
  {
    return std::min(p.gridRows - 1, int(uv.y() * p.gridRows / img.rows)) * p.gridCols +
           std::min(p.gridCols - 1, int(uv.x() * p.gridCols / img.cols));
  };
  std::vector<int> busy;
  for (const auto& o : occupied)
    if (o.x() >= 0 && o.y() >= 0) busy.push_back(cellOf(o));
  std::vector<int> used;
  for (size_t i = 0; i < corners.size(); ++i)
  {
    const auto& c = corners[i];
    EXPECT_GE(c.uv.x(), p.borderPx);
    EXPECT_GE(c.uv.y(), p.borderPx);
    EXPECT_LE(c.uv.x(), img.cols - 1 - p.borderPx);
    EXPECT_LE(c.uv.y(), img.rows - 1 - p.borderPx);
    EXPECT_GE(c.score, p.minShiTomasi);
    const int cell = cellOf(c.uv);
    EXPECT_EQ(std::count(busy.begin(), busy.end(), cell), 0) << "corner in an occupied cell";
    EXPECT_EQ(std::count(used.begin(), used.end(), cell), 0) << "two corners in one cell";
    used.push_back(cell);
    for (const auto& o : occupied) EXPECT_GE((c.uv - o).norm(), p.minDistancePx);
    for (size_t j = 0; j < i; ++j)
    {
      EXPECT_GE((c.uv - corners[j].uv).norm(), p.minDistancePx);
      EXPECT_GE(corners[j].score, c.score) << "not sorted strongest first";
    }
    EXPECT_NEAR(c.score, normalizedShiTomasi(img, int(c.uv.x()), int(c.uv.y())), 1e-12);
  }
  // Deterministic.
  const auto again = detectInEmptyCells(img, occupied, maxNew, p);
  ASSERT_EQ(again.size(), corners.size());
  for (size_t i = 0; i < corners.size(); ++i)
  {
    EXPECT_EQ(again[i].uv, corners[i].uv);
    EXPECT_EQ(again[i].score, corners[i].score);
  }
}

TEST(Detection, LensMaskKeepsCornersInsideAFisheyesImageCircle)
{
  // Pinhole and radial models image every pixel: no mask, no per-pixel pass.
  EXPECT_TRUE(lensMask(camera::CPinholeCamera(320, 240, 240, 240, 159.5, 119.5), 12).empty());
  EXPECT_TRUE(lensMask(camera::COpenCVCamera(752, 480, 458.654, 457.296, 367.215, 248.375, -0.28340811, 0.07395907,
                                             0.00019359, 1.76187114e-05, 0),
                       12)
                  .empty());
  // A 180-degree equidistant lens whose image circle (radius f pi/2 = 141 px) fits inside 320x320.
  const camera::CFisheyeCamera fe(320, 320, 90, 90, 159.5, 159.5, 0, 0, 0, 0);
  const int margin = 12;
  const cv::Mat mask = lensMask(fe, margin);
  ASSERT_FALSE(mask.empty());
  ASSERT_EQ(mask.type(), CV_8UC1);
  const double radius = 90 * M_PI / 2;
  for (int v = 0; v < 320; v += 3)
    for (int u = 0; u < 320; u += 3)
    {
      const double r = std::hypot(u - 159.5, v - 159.5);
      if (r < radius - margin - 1.5)
      {
        EXPECT_EQ(mask.at<std::uint8_t>(v, u), 255) << u << "," << v;
      }
      else if (r > radius - margin + 1.5)
      {
        EXPECT_EQ(mask.at<std::uint8_t>(v, u), 0) << u << "," << v;
      }
    }
  // Texture everywhere, as if the lens imaged the corners: corners only where the mask allows.
  const cv::Mat img = makeTexture(320, 320, 1);
  TDetectorParams p;
  const auto all = detectInEmptyCells(img, {}, 48, p);
  p.validMask = mask;
  const auto inside = detectInEmptyCells(img, {}, 48, p);
  ASSERT_GT(inside.size(), 10u);
  EXPECT_GT(std::count_if(all.begin(), all.end(), [&](const TCorner& c) { return !mask.at<std::uint8_t>(int(c.uv.y()), int(c.uv.x())); }), 0);
  for (const auto& c : inside) EXPECT_LT(std::hypot(c.uv.x() - 159.5, c.uv.y() - 159.5), radius - margin + 1.5);
  p.validMask = cv::Mat(10, 10, CV_8UC1, cv::Scalar(255));
  EXPECT_THROW(detectInEmptyCells(img, {}, 48, p), std::runtime_error);
}

TEST(Detection, ExclusionMaskGrowsByThePatchAndKeepsCornersOff)
{
  // One excluded pixel and a 20x10 excluded block: grown in a square of half size 5.
  cv::Mat ex(240, 320, CV_8UC1, cv::Scalar(0));
  ex.at<std::uint8_t>(50, 60) = 7;
  ex(cv::Rect(200, 100, 20, 10)).setTo(1);
  const cv::Mat g = growExclusion(ex, 5);
  ASSERT_EQ(g.type(), CV_8UC1);
  for (int v = 0; v < 240; ++v)
    for (int u = 0; u < 320; ++u)
    {
      const bool nearPixel = std::abs(u - 60) <= 5 && std::abs(v - 50) <= 5;
      const bool nearBlock = u >= 195 && u <= 224 && v >= 95 && v <= 114;
      ASSERT_EQ(g.at<std::uint8_t>(v, u) != 0, nearPixel || nearBlock) << u << "," << v;
    }
  // maskedAt rounds to the nearest pixel (doc/conventions.md) and is false off the image.
  EXPECT_TRUE(maskedAt(g, Vec2(65.4, 55.4)));
  EXPECT_FALSE(maskedAt(g, Vec2(65.6, 50)));
  EXPECT_FALSE(maskedAt(g, Vec2(-1, -1)));
  EXPECT_FALSE(maskedAt(g, Vec2(std::nan(""), 50)));
  EXPECT_FALSE(maskedAt(cv::Mat(), Vec2(60, 50)));
  EXPECT_TRUE(growExclusion(cv::Mat(), 5).empty());
  EXPECT_THROW(growExclusion(cv::Mat(10, 10, CV_32F, cv::Scalar(0)), 5), std::invalid_argument);
  EXPECT_THROW(growExclusion(ex, -1), std::invalid_argument);
  // As a detector mask (allowed = not excluded): no corner whose patch touches an excluded pixel.
  cv::Mat half(240, 320, CV_8UC1, cv::Scalar(0));
  half(cv::Rect(0, 0, 160, 240)).setTo(255);
  const cv::Mat img = makeTexture(320, 240, 4);
  TDetectorParams p;
  p.validMask = growExclusion(half, 5) == 0;
  const auto corners = detectInEmptyCells(img, {}, 40, p);
  ASSERT_GT(corners.size(), 5u);
  for (const auto& c : corners) EXPECT_GE(c.uv.x(), 165) << c.uv.transpose();
}

TEST(Detection, NothingOnFlatImageOrFullGridOrZeroRequest)
{
  TDetectorParams p;
  EXPECT_TRUE(detectInEmptyCells(cv::Mat(240, 320, CV_8UC1, cv::Scalar(90)), {}, 50, p).empty());
  cv::Mat noisy(240, 320, CV_8UC1);
  cv::RNG(3).fill(noisy, cv::RNG::NORMAL, 128, 2);  // sensor noise only
  EXPECT_TRUE(detectInEmptyCells(noisy, {}, 50, p).empty());
  const cv::Mat img = makeTexture(320, 240, 2);
  EXPECT_TRUE(detectInEmptyCells(img, {}, 0, p).empty());
  std::vector<Vec2> all;
  for (int r = 0; r < p.gridRows; ++r)
    for (int c = 0; c < p.gridCols; ++c)
      all.emplace_back((c + 0.5) * 320.0 / p.gridCols, (r + 0.5) * 240.0 / p.gridRows);
  EXPECT_TRUE(detectInEmptyCells(img, all, 50, p).empty());
  EXPECT_THROW(detectInEmptyCells(cv::Mat(10, 10, CV_8UC3), {}, 5, p), std::runtime_error);
}

TEST(Detection, ShiTomasiIsContrastInvariantAndRejectsEdges)
{
  // A bright square on a dark background, slightly blurred.
  cv::Mat img(100, 100, CV_8UC1, cv::Scalar(40));
  cv::rectangle(img, cv::Rect(30, 30, 40, 40), cv::Scalar(200), cv::FILLED);
  cv::GaussianBlur(img, img, cv::Size(0, 0), 0.7);
  const double corner = normalizedShiTomasi(img, 30, 30);
  const double edge = normalizedShiTomasi(img, 50, 30);
  const double flat = normalizedShiTomasi(img, 50, 50);
  std::printf("[ measure  ] normalized Shi-Tomasi: corner %.4f, straight edge %.5f, flat %.5f\n",
              corner, edge, flat);
  EXPECT_GT(corner, 0.05);
  EXPECT_LT(edge, 0.005);
  EXPECT_LT(flat, 1e-9);
  // Gain and offset change: same score (up to the +1 guard and 8-bit rounding).
  cv::Mat low;
  img.convertTo(low, CV_8U, 0.5, 60);
  EXPECT_NEAR(normalizedShiTomasi(low, 30, 30), corner, 0.05 * corner);
  // Ideal (unblurred) corner, for the documentation of minShiTomasi.
  cv::Mat sharp(100, 100, CV_8UC1, cv::Scalar(40));
  cv::rectangle(sharp, cv::Rect(30, 30, 40, 40), cv::Scalar(200), cv::FILLED);
  cv::Mat blur1;
  cv::GaussianBlur(sharp, blur1, cv::Size(0, 0), 1.0);
  std::printf("[ measure  ] ideal corner %.4f, blurred (sigma 1) %.4f\n",
              normalizedShiTomasi(sharp, 30, 30), normalizedShiTomasi(blur1, 30, 30));
  // Windows that do not fit give 0.
  EXPECT_EQ(normalizedShiTomasi(img, 2, 50), 0.0);
}

// ---------------------------------------------------------------------------------------------
// Patches
// ---------------------------------------------------------------------------------------------

TEST(Patch, OriginalTemplateIsTheSubpixelInterpolatedImage)
{
  const cv::Mat img = makeTexture(200, 150, 4);
  CFeaturePatch patch;
  EXPECT_FALSE(patch.valid());
  const Vec2 uv(80.37, 61.72);
  ASSERT_TRUE(patch.extract(img, uv, 5));
  EXPECT_EQ(patch.regionHalfSize(), 11);
  EXPECT_NEAR((patch.subpixelOffset() - Vec2(0.37, -0.28)).norm(), 0, 1e-12);
  const cv::Mat t = patch.originalTemplate();
  ASSERT_EQ(t.type(), CV_32F);
  ASSERT_EQ(t.rows, 11);
  cv::Mat ref;
  cv::getRectSubPix(img, cv::Size(11, 11), cv::Point2f(float(uv.x()), float(uv.y())), ref, CV_32F);
  // getRectSubPix uses fixed-point weights: agreement to a small fraction of a grey level.
  EXPECT_LT(cv::norm(t, ref, cv::NORM_INF), 0.3);

  // Does not fit: rejected, patch unchanged.
  EXPECT_FALSE(patch.extract(img, Vec2(5, 70), 5));
  EXPECT_FALSE(patch.extract(img, Vec2(NAN, 70), 5));
  EXPECT_NEAR(patch.subpixelOffset().x(), 0.37, 1e-12);

  // Saturation: singular or non-finite A never crash; NaN -> identity.
  const cv::Mat s = patch.predictTemplate(Mat2::Zero());
  EXPECT_TRUE(cv::checkRange(s));
  Mat2 nanA = Mat2::Identity();
  nanA(0, 1) = NAN;
  EXPECT_EQ(cv::norm(patch.predictTemplate(nanA), t, cv::NORM_INF), 0.0);
  const cv::Mat huge = patch.predictTemplate(Mat2::Identity() * 1e-9);
  EXPECT_TRUE(cv::checkRange(huge));
  // Copies are independent of later extractions.
  const CFeaturePatch copy = patch;
  ASSERT_TRUE(patch.extract(img, Vec2(120.1, 70.9), 5));
  EXPECT_EQ(cv::norm(copy.originalTemplate(), t, cv::NORM_INF), 0.0);
  // Reusing an output buffer.
  cv::Mat buf;
  patch.predictTemplate(Mat2::Identity(), buf);
  const void* data = buf.data;
  patch.predictTemplate(Mat2::Identity() * 1.1, buf);
  EXPECT_EQ(buf.data, data);
}

// ---------------------------------------------------------------------------------------------
// Search
// ---------------------------------------------------------------------------------------------

TEST(Search, FindsTheSubpixelPositionInTheSameImage)
{
  const cv::Mat img = makeTexture(320, 240, 5);
  const auto feats = featurePositions(img, 40, 6);
  ASSERT_GT(feats.size(), 25u);
  const Mat2 S = Vec2(9, 9).asDiagonal();
  for (const int iters : {0, 5})
  {
    TSearchParams sp;
    sp.refineIterations = iters;
    std::mt19937 rng(7);
    std::normal_distribution<double> N(0, 1.5);
    std::vector<double> errs;
    for (const Vec2& uv : feats)
    {
      CFeaturePatch patch;
      ASSERT_TRUE(patch.extract(img, uv, 5));
      const Vec2 h = uv + Vec2(N(rng), N(rng));
      if (!insideGate(uv, h, S, sp.gateChi2)) continue;
      const auto r = searchInEllipse(img, patch.originalTemplate(), h, S, sp);
      ASSERT_TRUE(r.found) << "at " << uv.transpose() << " score " << r.score;
      errs.push_back((r.uv - uv).norm());
      if (iters > 0)
      {
        EXPECT_LT(errs.back(), 0.1) << "at " << uv.transpose();
      }
    }
    std::printf("[ measure  ] identity, %s: median error %.3f px, max %.3f px (%zu features)\n",
                iters ? "quadratic + Gauss-Newton" : "quadratic fit only", median(errs),
                *std::max_element(errs.begin(), errs.end()), errs.size());
  }
}

TEST(Search, FindsAKnownSubpixelShift)
{
  const cv::Mat img = makeTexture(320, 240, 8);
  const Vec2 t(3.37, -2.61);
  cv::Mat M = (cv::Mat_<double>(2, 3) << 1, 0, t.x(), 0, 1, t.y());
  const cv::Mat img2 = warpImage(img, M);
  const auto feats = featurePositions(img, 40, 9);
  ASSERT_GT(feats.size(), 25u);
  TSearchWorkspace ws;
  const Mat2 S = Vec2(16, 16).asDiagonal();
  for (const int iters : {0, 5})
  {
    TSearchParams sp;
    sp.refineIterations = iters;
    std::vector<double> errs;
    for (const Vec2& uv : feats)
    {
      CFeaturePatch patch;
      ASSERT_TRUE(patch.extract(img, uv, 5));
      const Vec2 truth = uv + t;
      const auto r = searchInEllipse(img2, patch.originalTemplate(), uv + Vec2(3, -2), S, sp, ws);
      ASSERT_TRUE(r.found) << "at " << uv.transpose() << " score " << r.score;
      errs.push_back((r.uv - truth).norm());
      if (iters > 0)
      {
        EXPECT_LT(errs.back(), 0.2) << "at " << uv.transpose();
      }
    }
    std::printf(
        "[ measure  ] shift (3.37, -2.61), %s: median error %.3f px, max %.3f px (%zu "
        "features)\n",
        iters ? "quadratic + Gauss-Newton" : "quadratic fit only", median(errs),
        *std::max_element(errs.begin(), errs.end()), errs.size());
  }
}

namespace
{
struct TWarpStats
{
  int n = 0, foundWarped = 0, foundPlain = 0;
  double meanScoreWarped = 0, meanScorePlain = 0, maxErr = 0, medianErr = 0;
};

TWarpStats runWarpedMatching(const cv::Mat& img, const cv::Mat& M, unsigned seed, int iters)
{
  const cv::Mat img2 = warpImage(img, M);
  const Mat2 A = linearPart(M);
  const auto feats = featurePositions(img, 48, seed, 40);
  TSearchParams sp;
  sp.refineIterations = iters;
  TSearchWorkspace ws;
  const Mat2 S = Vec2(9, 9).asDiagonal();
  TWarpStats st;
  std::vector<double> errs;
  for (const Vec2& uv : feats)
  {
    const Vec2 truth = applyAffine(M, uv);
    if (truth.x() < 30 || truth.y() < 30 || truth.x() > img.cols - 30 || truth.y() > img.rows - 30)
      continue;
    CFeaturePatch patch;
    if (!patch.extract(img, uv, 5)) continue;
    ++st.n;
    const Vec2 h = truth + Vec2(1.2, -0.8);
    const auto rw = searchInEllipse(img2, patch.predictTemplate(A), h, S, sp, ws);
    const auto rp = searchInEllipse(img2, patch.originalTemplate(), h, S, sp, ws);
    st.meanScoreWarped += rw.score;
    st.meanScorePlain += rp.score;
    st.foundWarped += rw.found;
    st.foundPlain += rp.found;
    if (rw.found) errs.push_back((rw.uv - truth).norm());
  }
  st.meanScoreWarped /= std::max(st.n, 1);
  st.meanScorePlain /= std::max(st.n, 1);
  if (!errs.empty())
  {
    st.maxErr = *std::max_element(errs.begin(), errs.end());
    st.medianErr = median(errs);
  }
  return st;
}
}  // namespace

TEST(Search, WarpedPredictionFindsRotatedAndScaledFeatures)
{
  const cv::Mat img = makeTexture(320, 240, 10, 1.5);
  const cv::Point2f centre(160, 120);
  for (const auto& [angle, scale] : std::vector<std::pair<double, double>>{{30, 1.3}, {-45, 0.75}})
  {
    const cv::Mat M = cv::getRotationMatrix2D(centre, angle, scale);
    const TWarpStats q = runWarpedMatching(img, M, 11, 0);
    std::printf(
        "[ measure  ] rotation %.0f deg, scale %.2f, quadratic fit only: median error %.3f "
        "px, max %.3f px\n",
        angle, scale, q.medianErr, q.maxErr);
    const TWarpStats st = runWarpedMatching(img, M, 11, 5);
    std::printf(
        "[ measure  ] rotation %.0f deg, scale %.2f: %d features; warped template: found %d, "
        "mean ZNCC %.3f, median error %.3f px, max %.3f px; unwarped: found %d, mean ZNCC "
        "%.3f\n",
        angle, scale, st.n, st.foundWarped, st.meanScoreWarped, st.medianErr, st.maxErr,
        st.foundPlain, st.meanScorePlain);
    ASSERT_GE(st.n, 12);
    EXPECT_GE(st.foundWarped, st.n - 1);
    EXPECT_LT(st.maxErr, 0.3);
    EXPECT_GT(st.meanScoreWarped, 0.9);
    EXPECT_LT(st.meanScorePlain, st.meanScoreWarped - 0.1);
  }
}

TEST(Search, HonoursTheGateEllipse)
{
  // Fine texture: the correlation peak is narrow.
  const cv::Mat img = makeTexture(320, 240, 12, 0.8, 12);
  const auto feats = featurePositions(img, 20, 13);
  ASSERT_GT(feats.size(), 10u);
  TSearchParams sp;
  const Mat2 S = Vec2(4, 4).asDiagonal();  // gate radius sqrt(5.991 * 4) = 4.9 px
  int foundInside = 0;
  for (const Vec2& uv : feats)
  {
    CFeaturePatch patch;
    ASSERT_TRUE(patch.extract(img, uv, 5));
    const cv::Mat t = patch.originalTemplate();
    // True match at 6.5 px from the predicted position: just outside the gate.
    const Vec2 hOut = uv + Vec2(6.5, 0.0);
    ASSERT_FALSE(insideGate(uv, hOut, S, sp.gateChi2));
    const auto r = searchInEllipse(img, t, hOut, S, sp);
    if (r.found)
    {
      EXPECT_TRUE(insideGate(r.uv, hOut, S, sp.gateChi2));
      EXPECT_GT((r.uv - uv).norm(), 1.0) << "returned the match outside the gate";
    }
    EXPECT_LT(r.score, 0.999);
    // Just inside: found exactly.
    const Vec2 hIn = uv + Vec2(-3.2, 3.2);  // 4.5 px away
    const auto ri = searchInEllipse(img, t, hIn, S, sp);
    foundInside += ri.found && (ri.uv - uv).norm() < 0.1;
  }
  EXPECT_EQ(foundInside, int(feats.size()));
}

TEST(Search, EvaluatedCountMatchesTheEllipseArea)
{
  const cv::Mat img = makeTexture(320, 240, 14);
  CFeaturePatch patch;
  ASSERT_TRUE(patch.extract(img, Vec2(100.2, 80.7), 5));
  const cv::Mat t = patch.originalTemplate();
  TSearchParams sp;
  const Vec2 h(160.3, 120.6);
  for (const Mat2& S :
       {Mat2((Mat2() << 30, 10, 10, 20).finished()), Mat2((Mat2() << 60, -25, -25, 40).finished()),
        Mat2((Mat2() << 6, 1, 1, 3).finished())})
  {
    const auto r = searchInEllipse(img, t, h, S, sp);
    const double area = ellipseArea(S, sp.gateChi2);
    const int exact = latticeCount(h, S, sp.gateChi2, 0, 319, 0, 239);
    std::printf("[ measure  ] ellipse area %.1f px^2: %d positions evaluated\n", area, r.evaluated);
    EXPECT_EQ(r.evaluated, exact);
    if (area > 50)
    {
      EXPECT_NEAR(r.evaluated, area, 0.15 * area);
    }
  }
  EXPECT_NEAR(ellipseArea(Mat2::Identity() * 4), 3.14159265358979 * 5.991 * 4, 1e-9);
  EXPECT_EQ(ellipseArea(Mat2::Zero()), 0.0);
}

TEST(Search, ClipsAtImageBordersAndMaxExtent)
{
  const cv::Mat img = makeTexture(320, 240, 15);
  TSearchParams sp;
  // Feature near the left border; ellipse far beyond it.
  const Vec2 uv(12.4, 120.3);
  CFeaturePatch patch;
  ASSERT_TRUE(patch.extract(img, uv, 5));
  const cv::Mat t = patch.originalTemplate();
  const Mat2 S = Mat2::Identity() * 100;  // radius 24.5 px
  const Vec2 h(4.0, 118.0);
  const auto r = searchInEllipse(img, t, h, S, sp);
  EXPECT_TRUE(r.found);
  EXPECT_LT((r.uv - uv).norm(), 0.1);
  EXPECT_EQ(r.evaluated, latticeCount(h, S, sp.gateChi2, 5, 314, 5, 234));
  EXPECT_LT(r.evaluated, ellipseArea(S) * 0.7);

  // Bottom-right corner, template reaching the last row/column.
  const Vec2 uv2(307.6, 227.4);
  CFeaturePatch p2;
  ASSERT_TRUE(p2.extract(img, uv2, 5));
  const auto r2 = searchInEllipse(img, p2.originalTemplate(), Vec2(318, 238), S, sp);
  EXPECT_TRUE(r2.found);
  EXPECT_LT((r2.uv - uv2).norm(), 0.1);

  // Ellipse entirely outside the image: nothing evaluated.
  const auto r3 = searchInEllipse(img, t, Vec2(-80, -80), S, sp);
  EXPECT_FALSE(r3.found);
  EXPECT_EQ(r3.evaluated, 0);

  // Pathological S: the box is clipped to maxHalfExtentPx.
  sp.maxHalfExtentPx = 20;
  const Vec2 uv4(160.3, 120.8);
  CFeaturePatch p4;
  ASSERT_TRUE(p4.extract(img, uv4, 5));
  const Vec2 h4 = uv4 + Vec2(15, -12);
  const auto r4 = searchInEllipse(img, p4.originalTemplate(), h4, Mat2::Identity() * 1e6, sp);
  const int nx = int(std::floor(h4.x() + 20) - std::ceil(h4.x() - 20)) + 1;
  const int ny = int(std::floor(h4.y() + 20) - std::ceil(h4.y() - 20)) + 1;
  EXPECT_EQ(r4.evaluated, nx * ny);
  EXPECT_TRUE(r4.found);
  EXPECT_LT((r4.uv - uv4).norm(), 0.1);
}

TEST(Search, DirectZnccEqualsMatchTemplate)
{
  const cv::Mat img = makeTexture(320, 240, 17);
  std::mt19937 rng(18);
  std::uniform_real_distribution<double> U(0, 1);
  TSearchParams direct, ref;
  ref.useMatchTemplate = true;
  direct.ambiguityMargin = ref.ambiguityMargin = 0.03;
  TSearchWorkspace ws1, ws2;
  int found = 0;
  for (int k = 0; k < 300; ++k)
  {
    // Random features (anywhere, also near borders), predictions and covariances.
    const Vec2 uv(12 + U(rng) * 295, 12 + U(rng) * 215);
    CFeaturePatch patch;
    if (!patch.extract(img, uv, k % 3 == 0 ? 4 : 5)) continue;
    cv::Mat t = patch.originalTemplate();
    if (k % 5 == 0) t.convertTo(t, CV_8U);
    const double sxx = 1 + 80 * U(rng), syy = 1 + 80 * U(rng);
    const double sxy = (U(rng) - 0.5) * 1.8 * std::sqrt(sxx * syy);
    const Mat2 S = (Mat2() << sxx, sxy, sxy, syy).finished();
    const Vec2 h = uv + Vec2(U(rng) - 0.5, U(rng) - 0.5) * 2 * std::sqrt(std::max(sxx, syy));
    const auto a = searchInEllipse(img, t, h, S, direct, ws1);
    const auto b = searchInEllipse(img, t, h, S, ref, ws2);
    ASSERT_EQ(a.evaluated, b.evaluated) << k;
    ASSERT_EQ(a.found, b.found) << k;
    // matchTemplate correlates in float through the DFT of the whole ROI: its scores are off by up
    // to ~1e-3 on large ROIs (the direct sums agree with a double-precision ZNCC to ~2e-6).
    EXPECT_NEAR(a.score, b.score, 1e-3) << k;
    EXPECT_NEAR(a.secondScore, b.secondScore, 1e-3) << k;
    EXPECT_LT((a.uv - b.uv).norm(), 1e-3) << k;
    found += a.found;
  }
  EXPECT_GT(found, 100);
}

TEST(Search, FlatTemplatesAndFlatImagesNeverMatch)
{
  const cv::Mat img = makeTexture(320, 240, 16);
  const cv::Mat flatImg(240, 320, CV_8UC1, cv::Scalar(77));
  TSearchParams sp;
  const Mat2 S = Mat2::Identity() * 25;
  CFeaturePatch flatPatch;
  ASSERT_TRUE(flatPatch.extract(flatImg, Vec2(100, 100), 5));
  const auto r1 = searchInEllipse(img, flatPatch.originalTemplate(), Vec2(100, 100), S, sp);
  EXPECT_FALSE(r1.found);
  EXPECT_EQ(r1.evaluated, 0);
  const auto r1b = searchInEllipse(flatImg, flatPatch.originalTemplate(), Vec2(100, 100), S, sp);
  EXPECT_FALSE(r1b.found);
  CFeaturePatch p;
  ASSERT_TRUE(p.extract(img, Vec2(100.5, 100.5), 5));
  const auto r2 = searchInEllipse(flatImg, p.originalTemplate(), Vec2(100, 100), S, sp);
  EXPECT_FALSE(r2.found);
  EXPECT_LE(r2.score, 1e-3);
  // 8-bit templates are accepted too.
  const cv::Mat t8 = img(cv::Rect(95, 95, 11, 11)).clone();
  const auto r3 = searchInEllipse(img, t8, Vec2(102, 98), S, sp);
  EXPECT_TRUE(r3.found);
  EXPECT_LT((r3.uv - Vec2(100, 100)).norm(), 1e-3);
  // Bad inputs.
  EXPECT_THROW(searchInEllipse(img, p.originalTemplate(), Vec2(100, 100), -S, sp),
               std::runtime_error);
  EXPECT_THROW(searchInEllipse(img, cv::Mat(10, 10, CV_32F, cv::Scalar(1)), Vec2(100, 100), S, sp),
               std::runtime_error);
}
