/* Shared helpers of the frontend tests: synthetic images, affine maps, gate geometry, timing. */
#pragma once

#include <immslam/frontend/frontend.h>

#include <Eigen/LU>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

namespace immslam::frontend::test
{
/** Random textured image: filled blobs (discs and quadrilaterals) of random grey levels over
 * smooth noise, then blurred. Deterministic for a seed. */
inline cv::Mat makeTexture(int W, int H, unsigned seed, double blurSigma = 1.2, int blobsPerKpx = 7)
{
  cv::RNG rng(seed);
  cv::Mat lo(H / 8 + 2, W / 8 + 2, CV_32F);
  rng.fill(lo, cv::RNG::NORMAL, 128, 30);
  cv::Mat smooth;
  cv::resize(lo, smooth, cv::Size(W, H), 0, 0, cv::INTER_CUBIC);
  cv::Mat img;
  smooth.convertTo(img, CV_8U);
  const int nBlobs = W * H * blobsPerKpx / 1000;
  for (int i = 0; i < nBlobs; ++i)
  {
    const cv::Point c(rng.uniform(0, W), rng.uniform(0, H));
    const cv::Scalar col(rng.uniform(0, 256));
    const int r = rng.uniform(2, 12);
    if (rng.uniform(0, 2) == 0)
      cv::circle(img, c, r, col, cv::FILLED, cv::LINE_AA);
    else
    {
      std::vector<cv::Point> quad;
      for (int k = 0; k < 4; ++k)
      {
        const double a = k * CV_PI / 2 + rng.uniform(-0.5, 0.5);
        quad.emplace_back(c.x + int(r * std::cos(a)), c.y + int(r * std::sin(a)));
      }
      cv::fillConvexPoly(img, quad, col, cv::LINE_AA);
    }
  }
  if (blurSigma > 0) cv::GaussianBlur(img, img, cv::Size(0, 0), blurSigma);
  return img;
}

/** Image moved by the affine map M (2x3, uv_new = M [uv; 1]). */
inline cv::Mat warpImage(const cv::Mat& img, const cv::Mat& M)
{
  cv::Mat out;
  cv::warpAffine(img, out, M, img.size(), cv::INTER_CUBIC, cv::BORDER_REFLECT);
  return out;
}

inline Vec2 applyAffine(const cv::Mat& M, const Vec2& uv)
{
  return Vec2(M.at<double>(0, 0) * uv.x() + M.at<double>(0, 1) * uv.y() + M.at<double>(0, 2),
              M.at<double>(1, 0) * uv.x() + M.at<double>(1, 1) * uv.y() + M.at<double>(1, 2));
}

inline Mat2 linearPart(const cv::Mat& M)
{
  Mat2 A;
  A << M.at<double>(0, 0), M.at<double>(0, 1), M.at<double>(1, 0), M.at<double>(1, 1);
  return A;
}

inline bool insideGate(const Vec2& uv, const Vec2& h, const Mat2& S, double g)
{
  const Vec2 d = uv - h;
  return d.dot(S.inverse() * d) <= g;
}

/** Number of integer positions inside the gate (brute force), optionally restricted to a box. */
inline int latticeCount(const Vec2& h, const Mat2& S, double g, int xmin, int xmax, int ymin,
                        int ymax)
{
  int n = 0;
  for (int y = ymin; y <= ymax; ++y)
    for (int x = xmin; x <= xmax; ++x) n += insideGate(Vec2(x, y), h, S, g);
  return n;
}

/** Feature positions for the matching tests: detected corners plus a random sub-pixel offset. */
inline std::vector<Vec2> featurePositions(const cv::Mat& img, int maxN, unsigned seed,
                                          int border = 30)
{
  TDetectorParams dp;
  dp.borderPx = border;
  dp.gridCols = 8;
  dp.gridRows = 6;
  const auto corners = detectInEmptyCells(img, {}, maxN, dp);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(-0.5, 0.5);
  std::vector<Vec2> out;
  for (const auto& c : corners) out.push_back(c.uv + Vec2(U(rng), U(rng)));
  return out;
}

inline double median(std::vector<double> v)
{
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

inline std::string sharedData()
{
  return IMMSLAM_SHARED_DATA_DIR;
}

inline cv::Mat loadGrey(const std::string& path)
{
  cv::Mat img = cv::imread(path, cv::IMREAD_GRAYSCALE);
  return img;
}
}  // namespace immslam::frontend::test
