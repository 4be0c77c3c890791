/* imm-monoslam — sub-pixel refinement of a correlation peak: 2-D quadratic fit of the 3x3 scores,
 * then a Gauss-Newton polish of the translation (with photometric gain and offset). */
#include "search_detail.h"

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace immslam::frontend::detail
{
bool quadraticPeak(const float s[3][3], Vec2& offset)
{
  // f(x, y) = a + b x + c y + d x^2 + e x y + g y^2 fitted to the 9 samples (closed form).
  double sx = 0, sy = 0, sxy = 0, col0 = 0, colPm = 0, row0 = 0, rowPm = 0;
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i)
    {
      const double v = s[j][i];
      const int x = i - 1, y = j - 1;
      sx += x * v;
      sy += y * v;
      sxy += x * y * v;
      (x == 0 ? col0 : colPm) += v;
      (y == 0 ? row0 : rowPm) += v;
    }
  const double b = sx / 6, c = sy / 6, e = sxy / 4;
  const double d = colPm / 6 - col0 / 3, g = rowPm / 6 - row0 / 3;
  // Stationary point: [2d e; e 2g] [x; y] = -[b; c]; a maximum needs a negative definite Hessian.
  const double hxx = 2 * d, hyy = 2 * g, det = hxx * hyy - e * e;
  if (!(hxx < 0 && det > 0)) return false;
  offset = Vec2(-(hyy * b - e * c) / det, -(-e * b + hxx * c) / det);
  return offset.allFinite() && offset.norm() <= 1.0;
}

namespace
{
/** The (n + 2) x (m + 2) window of `grey` centred at p, bilinearly interpolated, into win (one
 * extra pixel each side for the gradients); false when it is not inside the image. */
bool sampleWindow(const cv::Mat& grey, const Vec2& p, int n, int m, std::vector<float>& win)
{
  const int htx = n / 2, hty = m / 2, wn = n + 2, wm = m + 2;
  const double flx = std::floor(p.x()), fly = std::floor(p.y());
  const int left = int(flx) - htx - 1, top = int(fly) - hty - 1;
  if (left < 0 || top < 0 || left + wn >= grey.cols || top + wm >= grey.rows) return false;
  const float fx = float(p.x() - flx), fy = float(p.y() - fly);
  const float w00 = (1 - fx) * (1 - fy), w01 = fx * (1 - fy), w10 = (1 - fx) * fy, w11 = fx * fy;
  for (int j = 0; j < wm; ++j)
  {
    const std::uint8_t* r0 = grey.ptr<std::uint8_t>(top + j) + left;
    const std::uint8_t* r1 = grey.ptr<std::uint8_t>(top + j + 1) + left;
    float* w = &win[size_t(j) * wn];
    for (int i = 0; i < wn; ++i)
      w[i] = w00 * r0[i] + w01 * r0[i + 1] + w10 * r1[i] + w11 * r1[i + 1];
  }
  return true;
}

/** The photometric start of refineTranslation(): gain a and offset b that match the window's
 * (win, n x m inside its 1-pixel border) mean and standard deviation to the template's (from its
 * sums tt = sum T^2 and ts = sum T). */
void photometricStart(const std::vector<float>& win, int n, int m, double tt, double ts, double& a, double& b)
{
  const int wn = n + 2;
  const double N = double(n) * m;
  double si = 0, sii = 0;
  for (int j = 0; j < m; ++j)
  {
    const float* w = &win[size_t(j + 1) * wn + 1];
    for (int i = 0; i < n; ++i)
    {
      si += w[i];
      sii += double(w[i]) * w[i];
    }
  }
  const double mi = si / N, mt = ts / N;
  const double vi = std::max(sii / N - mi * mi, 0.0), vt = std::max(tt / N - mt * mt, 1e-12);
  a = std::sqrt(vi / vt);
  b = mi - a * mt;
}
}  // namespace

bool refineTranslation(const cv::Mat& grey, const cv::Mat& T, Vec2& uv, int maxIter,
                       std::vector<float>& win)
{
  const int n = T.cols, m = T.rows;
  const int wn = n + 2, wm = m + 2;  // one extra pixel each side for the gradients
  win.resize(size_t(wn) * wm);
  // Constant blocks of J^T J: sum T^2, sum T, number of pixels.
  double tt = 0, ts = 0;
  for (int j = 0; j < m; ++j)
  {
    const float* t = T.ptr<float>(j);
    for (int i = 0; i < n; ++i)
    {
      tt += double(t[i]) * t[i];
      ts += t[i];
    }
  }
  const double N = double(n) * m;
  Vec2 p = uv;
  double a = 1, b = 0;
  for (int it = 0; it < maxIter; ++it)
  {
    if (!sampleWindow(grey, p, n, m, win)) return false;
    if (it == 0) photometricStart(win, n, m, tt, ts, a, b);  // match the window's mean and deviation
    // Normal equations of r = I(p + x) - a T(x) - b in (p, a, b); J = [dI/du, dI/dv, -T, -1].
    double gxx = 0, gxy = 0, gyy = 0, gxt = 0, gyt = 0, gx1 = 0, gy1 = 0;  // J^T J
    double rx = 0, ry = 0, rt = 0, r1 = 0;                                 // J^T r
    for (int j = 0; j < m; ++j)
    {
      const float* t = T.ptr<float>(j);
      const float* w = &win[size_t(j + 1) * wn + 1];
      const float* wu = w - wn;
      const float* wd = w + wn;
      for (int i = 0; i < n; ++i)
      {
        const double gx = 0.5 * (w[i + 1] - w[i - 1]), gy = 0.5 * (wd[i] - wu[i]), ti = t[i];
        const double r = w[i] - a * ti - b;
        gxx += gx * gx;
        gxy += gx * gy;
        gyy += gy * gy;
        gxt += gx * ti;
        gyt += gy * ti;
        gx1 += gx;
        gy1 += gy;
        rx += gx * r;
        ry += gy * r;
        rt += ti * r;
        r1 += r;
      }
    }
    Eigen::Matrix4d H;
    H << gxx, gxy, -gxt, -gx1,  //
        gxy, gyy, -gyt, -gy1,   //
        -gxt, -gyt, tt, ts,     //
        -gx1, -gy1, ts, N;
    const Eigen::Vector4d g(rx, ry, -rt, -r1);
    const Eigen::Vector4d delta = -H.ldlt().solve(g);
    if (!delta.allFinite() || delta.head<2>().norm() > 2.0) return false;
    p += delta.head<2>();
    a += delta[2];
    b += delta[3];
    if (delta.head<2>().squaredNorm() < 1e-6) break;
  }
  uv = p;
  return true;
}
}  // namespace immslam::frontend::detail
