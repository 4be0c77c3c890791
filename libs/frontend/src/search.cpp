/* imm-monoslam — active search of a template inside the gate ellipse of its innovation covariance
 * (IMM paper Sec. IV-1; MonoSLAM active search). */
#include "search_detail.h"

#include <Eigen/LU>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace immslam::frontend
{
namespace
{
/** A second peak must be at least this far (Chebyshev, px) from the best to count as distinct. */
constexpr int kAmbiguityMinSeparationPx = 3;
constexpr double kPi = 3.14159265358979323846;

void requireInputs(const cv::Mat& grey, const cv::Mat& templ, const Mat2& S)
{
  if (grey.empty() || grey.type() != CV_8UC1)
    throw std::runtime_error("frontend::searchInEllipse: expected a non-empty CV_8UC1 image");
  if (templ.empty() || (templ.type() != CV_32FC1 && templ.type() != CV_8UC1) ||
      templ.cols % 2 == 0 || templ.rows % 2 == 0)
    throw std::runtime_error(
        "frontend::searchInEllipse: the template must be CV_32FC1 or CV_8UC1 with odd sides");
  if (!S.allFinite() || !(S(0, 0) > 0) || !(S(1, 1) > 0) || !(S.determinant() > 0))
    throw std::runtime_error(
        "frontend::searchInEllipse: the innovation covariance S is not finite positive definite");
}

/** The gate of a search: inside the ellipse (u - h)^T S^-1 (u - h) <= g. */
struct TGate
{
  Vec2 h;
  Mat2 Sinv;
  double g;
  bool operator()(double x, double y) const
  {
    const double du = x - h.x(), dv = y - h.y();
    return Sinv(0, 0) * du * du + 2 * Sinv(0, 1) * du * dv + Sinv(1, 1) * dv * dv <= g;
  }
};

/** The score map's rows to compute (ws.rowLo, ws.rowHi for rows sy0..sy1): the gate's rows y0..y1,
 * each over the ellipse's span in that row and its two neighbours, within sx0..sx1. */
void ellipseRowSpans(const TGate& gate, int y0, int y1, int sx0, int sy0, int sx1, int sy1, TSearchWorkspace& ws)
{
  // Only the ellipse's rows, each over the ellipse's span in that row and its two neighbours,
  // grown by 2 px (1 px for the 3x3 neighbourhoods, 1 px against rounding at the boundary).
  const int rows = sy1 - sy0 + 1;
  ws.rowLo.assign(size_t(rows), std::numeric_limits<int>::max());
  ws.rowHi.assign(size_t(rows), std::numeric_limits<int>::min());
  const double a = gate.Sinv(0, 0), b = gate.Sinv(0, 1), c = gate.Sinv(1, 1), g = gate.g;
  const Vec2& h = gate.h;
  for (int y = y0; y <= y1; ++y)
  {
    // a du^2 + 2 b dv du + c dv^2 <= g, solved for du.
    const double dv = y - h.y();
    const double disc = b * b * dv * dv - a * (c * dv * dv - g);
    if (disc < 0) continue;
    const double sq = std::sqrt(disc);
    const int lo = int(std::max(std::floor(h.x() + (-b * dv - sq) / a), double(sx0))) - 1;
    const int hi = int(std::min(std::ceil(h.x() + (-b * dv + sq) / a), double(sx1))) + 1;
    for (int r = std::max(y - 1, sy0); r <= std::min(y + 1, sy1); ++r)
    {
      ws.rowLo[size_t(r - sy0)] = std::min(ws.rowLo[size_t(r - sy0)], lo);
      ws.rowHi[size_t(r - sy0)] = std::max(ws.rowHi[size_t(r - sy0)], hi);
    }
  }
}

/** The sub-pixel offset of the peak at (bx, by) added to uv: a quadratic fit on its 3x3
 * neighbourhood, when it is inside the score map sc (of positions sx0..sx1, sy0..sy1) and computed. */
void subpixelPeak(const cv::Mat& sc, int bx, int by, int sx0, int sy0, int sx1, int sy1, Vec2& uv)
{
  if (bx > sx0 && bx < sx1 && by > sy0 && by < sy1)
  {
    float s3[3][3];
    bool complete = true;
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i)
      {
        s3[j][i] = sc.at<float>(by - 1 + j - sy0, bx - 1 + i - sx0);
        complete = complete && s3[j][i] != detail::kNotComputed;
      }
    Vec2 off;
    if (complete && detail::quadraticPeak(s3, off)) uv += off;
  }
}

/** The best 3x3 local maximum of the score map sc inside the gate (positions x0..x1, y0..y1 of the
 * map's sx0..sx1, sy0..sy1) at least kAmbiguityMinSeparationPx from the peak (bx, by); -inf if none. */
float secondPeak(const cv::Mat& sc, const TGate& inGate, int x0, int y0, int x1, int y1, int sx0, int sy0, int sx1,
                 int sy1, int bx, int by)
{
  float second = -std::numeric_limits<float>::infinity();
  for (int y = y0; y <= y1; ++y)
  {
    const float* row = sc.ptr<float>(y - sy0) - sx0;
    for (int x = x0; x <= x1; ++x)
    {
      const float v = row[x];
      if (v <= second || std::max(std::abs(x - bx), std::abs(y - by)) < kAmbiguityMinSeparationPx ||
          !inGate(x, y))
        continue;
      bool isMax = true;
      for (int j = std::max(y - 1, sy0); j <= std::min(y + 1, sy1) && isMax; ++j)
      {
        const float* r = sc.ptr<float>(j - sy0) - sx0;
        for (int i = std::max(x - 1, sx0); i <= std::min(x + 1, sx1); ++i)
          if ((i != x || j != y) && r[i] > v)
          {
            isMax = false;
            break;
          }
      }
      if (isMax) second = v;
    }
  }
  return second;
}

/** The score map ws.scores over positions sx0..sx1, sy0..sy1: cv::matchTemplate over all of it,
 * or the ZNCC of the gate's rows y0..y1 only (detail::znccScoreRows). */
void scoreMap(const cv::Mat& grey, const cv::Mat& templ, const TGate& gate, bool useMatchTemplate, int y0, int y1,
              int sx0, int sy0, int sx1, int sy1, TSearchWorkspace& ws)
{
  const int htx = templ.cols / 2, hty = templ.rows / 2;
  if (useMatchTemplate)
  {
    const cv::Rect roi(sx0 - htx, sy0 - hty, sx1 - sx0 + 1 + 2 * htx, sy1 - sy0 + 1 + 2 * hty);
    if (templ.depth() == CV_8U)
      cv::matchTemplate(grey(roi), templ, ws.scores, cv::TM_CCOEFF_NORMED);
    else
    {
      grey(roi).convertTo(ws.roi, CV_32F);
      cv::matchTemplate(ws.roi, templ, ws.scores, cv::TM_CCOEFF_NORMED);
    }
  }
  else
  {
    ellipseRowSpans(gate, y0, y1, sx0, sy0, sx1, sy1, ws);
    detail::znccScoreRows(grey, templ, sx0, sy0, sx1, sy1, ws.rowLo, ws.rowHi, ws);
  }
}
}  // namespace

double ellipseArea(const Mat2& S, double gateChi2)
{
  const double det = S.determinant();
  return det > 0 ? kPi * gateChi2 * std::sqrt(det) : 0.0;
}

TSearchResult searchInEllipse(const cv::Mat& grey, const cv::Mat& templ, const Vec2& h,
                              const Mat2& S, const TSearchParams& p)
{
  TSearchWorkspace ws;
  return searchInEllipse(grey, templ, h, S, p, ws);
}

TSearchResult searchInEllipse(const cv::Mat& grey, const cv::Mat& templ, const Vec2& h,
                              const Mat2& S, const TSearchParams& p, TSearchWorkspace& ws)
{
  requireInputs(grey, templ, S);
  TSearchResult res;
  if (!h.allFinite()) return res;

  // Flat templates never match (ZNCC undefined).
  cv::Scalar mean, stddev;
  cv::meanStdDev(templ, mean, stddev);
  if (!(stddev[0] >= p.minTemplateStd)) return res;

  const int htx = templ.cols / 2, hty = templ.rows / 2;
  const Mat2 Sinv = S.inverse();
  const double g = p.gateChi2;
  const TGate inGate{h, Sinv, g};
  // Bounding box of the ellipse: half extents sqrt(g S_ii), clipped to maxHalfExtentPx.
  const double ex = std::min(std::sqrt(g * S(0, 0)), p.maxHalfExtentPx);
  const double ey = std::min(std::sqrt(g * S(1, 1)), p.maxHalfExtentPx);
  // Candidate centres: inside the box and with the whole template inside the image.
  const int x0 = std::max(int(std::ceil(h.x() - ex)), htx);
  const int x1 = std::min(int(std::floor(h.x() + ex)), grey.cols - 1 - htx);
  const int y0 = std::max(int(std::ceil(h.y() - ey)), hty);
  const int y1 = std::min(int(std::floor(h.y() + ey)), grey.rows - 1 - hty);
  if (x0 > x1 || y0 > y1) return res;
  // The score map reaches one pixel beyond the candidates (3x3 refinement, local maxima), where
  // the image allows: sc(y - sy0, x - sx0) is the score at position (x, y).
  const int sx0 = std::max(x0 - 1, htx), sx1 = std::min(x1 + 1, grey.cols - 1 - htx);
  const int sy0 = std::max(y0 - 1, hty), sy1 = std::min(y1 + 1, grey.rows - 1 - hty);

  scoreMap(grey, templ, inGate, p.useMatchTemplate, y0, y1, sx0, sy0, sx1, sy1, ws);
  const cv::Mat& sc = ws.scores;

  // Best integer position inside the ellipse.
  float best = -std::numeric_limits<float>::infinity();
  int bx = -1, by = -1;
  for (int y = y0; y <= y1; ++y)
  {
    const float* row = sc.ptr<float>(y - sy0) - sx0;
    for (int x = x0; x <= x1; ++x)
    {
      if (!inGate(x, y)) continue;
      ++res.evaluated;
      if (row[x] > best)
      {
        best = row[x];
        bx = x;
        by = y;
      }
    }
  }
  if (res.evaluated == 0) return res;
  res.score = best;
  res.uv = Vec2(bx, by);

  // Sub-pixel: quadratic fit on the 3x3 neighbourhood (if inside the score map and computed).
  subpixelPeak(sc, bx, by, sx0, sy0, sx1, sy1, res.uv);
  // Gauss-Newton polish from there, kept only if it stays within 1 px of the integer peak.
  if (p.refineIterations > 0)
  {
    const cv::Mat* tf = &templ;
    if (templ.depth() != CV_32F)
    {
      templ.convertTo(ws.templ32, CV_32F);
      tf = &ws.templ32;
    }
    Vec2 uv = res.uv;
    if (detail::refineTranslation(grey, *tf, uv, p.refineIterations, ws.window) &&
        (uv - Vec2(bx, by)).cwiseAbs().maxCoeff() <= 1.0)
      res.uv = uv;
  }

  // Second distinct peak: a 3x3 local maximum inside the ellipse, away from the best.
  const float second = secondPeak(sc, inGate, x0, y0, x1, y1, sx0, sy0, sx1, sy1, bx, by);
  if (std::isfinite(second)) res.secondScore = second;

  const bool ambiguous = p.ambiguityMargin > 0 && res.secondScore >= res.score - p.ambiguityMargin;
  res.found = res.score >= p.minScore && inGate(res.uv.x(), res.uv.y()) && !ambiguous;
  return res;
}
}  // namespace immslam::frontend
