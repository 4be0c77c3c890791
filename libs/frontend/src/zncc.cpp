/* imm-monoslam — direct zero-mean normalized cross-correlation on selected rows of a score map. */
#include "search_detail.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace immslam::frontend::detail
{
namespace
{
/** acc[x] += sum_i t[i] src[x + i] for x < L, with the template width NT known at compile time:
 * the i loop unrolls and the x loop vectorizes. */
template <int NT>
void crossRowFixed(float* __restrict acc, const float* __restrict src, const float* __restrict t,
                   int L)
{
  float tr[NT];
  for (int i = 0; i < NT; ++i) tr[i] = t[i];
  for (int x = 0; x < L; ++x)
  {
    float s = 0;
    for (int i = 0; i < NT; ++i) s += tr[i] * src[x + i];
    acc[x] += s;
  }
}

/** The same for any width: one template pixel at a time over the row segment. */
void crossRowAny(float* __restrict acc, const float* __restrict src, const float* __restrict t,
                 int n, int L)
{
  for (int i = 0; i < n; ++i)
  {
    const float ti = t[i];
    const float* __restrict s = src + i;
    for (int x = 0; x < L; ++x) acc[x] += ti * s[x];
  }
}

void crossRow(float* acc, const float* src, const float* t, int n, int L)
{
  switch (n)
  {
    case 7:
      return crossRowFixed<7>(acc, src, t, L);
    case 9:
      return crossRowFixed<9>(acc, src, t, L);
    case 11:
      return crossRowFixed<11>(acc, src, t, L);
    case 13:
      return crossRowFixed<13>(acc, src, t, L);
    case 15:
      return crossRowFixed<15>(acc, src, t, L);
    default:
      return crossRowAny(acc, src, t, n, L);
  }
}

/** The zero-mean template T' into ws.zeroMeanTemplate; returns sum T'^2. Then
 * sum_x I T' = sum_x (I - mean I) T'. */
double zeroMeanTemplate(const cv::Mat& templ, TSearchWorkspace& ws)
{
  const int n = templ.cols, m = templ.rows, N = n * m;
  ws.zeroMeanTemplate.resize(size_t(N));
  double tsum = 0;
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < n; ++i)
      tsum += templ.depth() == CV_8U ? double(templ.at<std::uint8_t>(j, i)) : templ.at<float>(j, i);
  const double tmean = tsum / N;
  double t2 = 0;
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < n; ++i)
    {
      const double t =
          (templ.depth() == CV_8U ? double(templ.at<std::uint8_t>(j, i)) : templ.at<float>(j, i)) -
          tmean;
      ws.zeroMeanTemplate[size_t(j * n + i)] = float(t);
      t2 += t * t;
    }
  return t2;
}

/** The RW x RH image ROI at (left, top) as float (ws.roiFloat) and the exact integral images of I
 * and I^2 (ws.integral, ws.integralSq; 8-bit input: integer sums), RW + 1 columns each. */
void roiIntegrals(const cv::Mat& grey, int left, int top, int RW, int RH, TSearchWorkspace& ws)
{
  ws.roiFloat.resize(size_t(RW) * RH);
  const size_t IW = size_t(RW) + 1;
  ws.integral.assign(IW * (RH + 1), 0);
  ws.integralSq.assign(IW * (RH + 1), 0);
  for (int j = 0; j < RH; ++j)
  {
    const std::uint8_t* src = grey.ptr<std::uint8_t>(top + j) + left;
    float* dst = &ws.roiFloat[size_t(j) * RW];
    std::int64_t rs = 0, rs2 = 0;
    const std::int64_t* up = &ws.integral[size_t(j) * IW];
    const std::int64_t* up2 = &ws.integralSq[size_t(j) * IW];
    std::int64_t* cur = &ws.integral[size_t(j + 1) * IW];
    std::int64_t* cur2 = &ws.integralSq[size_t(j + 1) * IW];
    for (int i = 0; i < RW; ++i)
    {
      const int v = src[i];
      dst[i] = float(v);
      rs += v;
      rs2 += v * v;
      cur[i + 1] = up[i + 1] + rs;
      cur2[i + 1] = up2[i + 1] + rs2;
    }
  }
}
}  // namespace

void znccScoreRows(const cv::Mat& grey, const cv::Mat& templ, int sx0, int sy0, int sx1, int sy1,
                   const std::vector<int>& lo, const std::vector<int>& hi, TSearchWorkspace& ws)
{
  const int n = templ.cols, m = templ.rows, htx = n / 2, hty = m / 2;
  const int N = n * m;
  const int mapW = sx1 - sx0 + 1, mapH = sy1 - sy0 + 1;
  const int RW = mapW + 2 * htx, RH = mapH + 2 * hty;  // the image ROI under the box
  const int left = sx0 - htx, top = sy0 - hty;

  const double t2 = zeroMeanTemplate(templ, ws);

  roiIntegrals(grey, left, top, RW, RH, ws);
  const size_t IW = size_t(RW) + 1;

  // The score map is a header over a growing buffer: no allocation once the buffer is big enough.
  if (ws.scoreBuffer.size() < size_t(mapW) * mapH) ws.scoreBuffer.resize(size_t(mapW) * mapH);
  std::fill(ws.scoreBuffer.begin(), ws.scoreBuffer.begin() + size_t(mapW) * mapH, kNotComputed);
  ws.scores = cv::Mat(mapH, mapW, CV_32F, ws.scoreBuffer.data());
  ws.accumulator.resize(size_t(mapW));
  float* acc = ws.accumulator.data();
  const float* tz = ws.zeroMeanTemplate.data();
  for (int r = 0; r < mapH; ++r)
  {
    const int c0 = std::max(lo[size_t(r)], sx0) - sx0, c1 = std::min(hi[size_t(r)], sx1) - sx0;
    if (c0 > c1) continue;
    const int L = c1 - c0 + 1;
    std::fill(acc, acc + L, 0.0f);
    // Cross term sum_j sum_i T'(j, i) I(r + j, c + i) for the row segment.
    for (int j = 0; j < m; ++j)
      crossRow(acc, &ws.roiFloat[size_t(r + j) * RW + c0], tz + j * n, n, L);
    float* out = ws.scores.ptr<float>(r);
    const std::int64_t* I0 = &ws.integral[size_t(r) * IW];
    const std::int64_t* I1 = &ws.integral[size_t(r + m) * IW];
    const std::int64_t* Q0 = &ws.integralSq[size_t(r) * IW];
    const std::int64_t* Q1 = &ws.integralSq[size_t(r + m) * IW];
    for (int x = 0; x < L; ++x)
    {
      const int c = c0 + x;
      const double s1 = double(I1[c + n] - I0[c + n] - I1[c] + I0[c]);
      const double s2 = double(Q1[c + n] - Q0[c + n] - Q1[c] + Q0[c]);
      const double v = s2 - s1 * s1 / N;  // N var(I): 0 for a flat window, >= ~1 otherwise
      out[c] = v > 0.5 && t2 > 0 ? float(acc[x] / std::sqrt(v * t2)) : 0.0f;
    }
  }
}
}  // namespace immslam::frontend::detail
