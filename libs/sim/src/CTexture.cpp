/* imm-monoslam — procedural textures (see CTexture.h). */
#include <immslam/sim/CRandom.h>
#include <immslam/sim/CTexture.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace immslam::sim
{
namespace
{
/** Adds value noise of cell size `cell` texels and amplitude `amp` (grey levels) to img (CV_32F). */
void addValueNoise(cv::Mat& img, double cell, double amp, CRandom& rng)
{
  const int gw = std::max(2, static_cast<int>(std::ceil(img.cols / cell)) + 1);
  const int gh = std::max(2, static_cast<int>(std::ceil(img.rows / cell)) + 1);
  cv::Mat grid(gh, gw, CV_32F);
  for (int y = 0; y < gh; ++y)
    for (int x = 0; x < gw; ++x) grid.at<float>(y, x) = static_cast<float>(rng.uniform(-amp, amp));
  cv::Mat up;
  cv::resize(grid, up, img.size(), 0, 0, cv::INTER_CUBIC);
  img += up;
}

struct TShape
{
  int kind;
  double size;  // units
};

cv::Point toPt(double x, double y) { return cv::Point(static_cast<int>(std::lround(x * 16)), static_cast<int>(std::lround(y * 16))); }

/** Draws shape s at a random place of img (sizes in texels: s.size times tpu), a random grey about
 * `mean` within `contrast`. */
void drawShape(cv::Mat& img, const TShape& s, double tpu, double mean, double contrast, CRandom& rng)
{
  const int W = img.cols, H = img.rows;
  const double cx = rng.uniform(0.0, W), cy = rng.uniform(0.0, H);
  const double a = s.size * tpu * rng.uniform(0.5, 1.0);  // half-extent-ish in texels
  const double b = s.size * tpu * rng.uniform(0.25, 1.0);
  const int grey = static_cast<int>(std::clamp(mean + contrast * rng.uniform(-1.0, 1.0), 0.0, 255.0));
  const cv::Scalar col(grey);
  if (s.kind < 35)
  {  // axis-aligned filled rectangle
    cv::rectangle(img, toPt(cx - a, cy - b), toPt(cx + a, cy + b), col, cv::FILLED, cv::LINE_8, 4);
  }
  else if (s.kind < 45)
  {  // hollow rectangle
    const int th = std::max(1, static_cast<int>(std::lround(rng.uniform(0.1, 0.3) * std::min(a, b))));
    cv::rectangle(img, toPt(cx - a, cy - b), toPt(cx + a, cy + b), col, th, cv::LINE_8, 4);
  }
  else if (s.kind < 60)
  {  // rotated rectangle
    const double ang = rng.uniform(0.0, M_PI);
    const double c = std::cos(ang), sn = std::sin(ang);
    cv::Point pts[4];
    const double dx[4] = {-a, a, a, -a}, dy[4] = {-b, -b, b, b};
    for (int i = 0; i < 4; ++i) pts[i] = toPt(cx + c * dx[i] - sn * dy[i], cy + sn * dx[i] + c * dy[i]);
    cv::fillConvexPoly(img, pts, 4, col, cv::LINE_AA, 4);
  }
  else if (s.kind < 72)
  {  // small checkerboard patch
    const int cells = rng.uniformInt(2, 5);
    const double cell = 2.0 * a / cells;
    const int g2 = std::clamp(grey + (grey < 128 ? 1 : -1) * rng.uniformInt(60, 150), 0, 255);
    for (int i = 0; i < cells; ++i)
      for (int j = 0; j < cells; ++j)
      {
        const double x0 = cx - a + i * cell, y0 = cy - a + j * cell;
        cv::rectangle(img, toPt(x0, y0), toPt(x0 + cell, y0 + cell), cv::Scalar((i + j) % 2 ? grey : g2),
                      cv::FILLED, cv::LINE_8, 4);
      }
  }
  else if (s.kind < 88)
  {  // triangle or quadrilateral with random corners
    const int nv = rng.uniformInt(3, 4);
    cv::Point pts[4];
    const double a0 = rng.uniform(0.0, 2 * M_PI);
    for (int i = 0; i < nv; ++i)
    {
      const double ang = a0 + (2 * M_PI * i) / nv + rng.uniform(-0.5, 0.5);
      const double rad = a * rng.uniform(0.6, 1.0);
      pts[i] = toPt(cx + rad * std::cos(ang), cy + rad * std::sin(ang));
    }
    cv::fillConvexPoly(img, pts, nv, col, cv::LINE_AA, 4);
  }
  else
  {  // ellipse (a blob)
    cv::ellipse(img, toPt(cx, cy), cv::Size(static_cast<int>(a * 16), static_cast<int>(b * 16)),
                rng.uniform(0.0, 180.0), 0, 360, col, cv::FILLED, cv::LINE_AA, 4);
  }
}
}  // namespace

CTexture CTexture::generate(double width, double height, double texelsPerUnit, double shapesPerUnit2,
                            std::uint64_t seed)
{
  CTexture tex;
  tex.m_tpu = texelsPerUnit;
  const int W = std::max(2, static_cast<int>(std::ceil(width * texelsPerUnit)));
  const int H = std::max(2, static_cast<int>(std::ceil(height * texelsPerUnit)));
  CRandom rng(seed);

  // Per-surface style: density, mean grey and contrast, so surfaces differ.
  const double densityMul = rng.logUniform(0.5, 1.6);
  const double mean = rng.uniform(80.0, 175.0);
  const double contrast = rng.uniform(60.0, 127.0);

  // 1. Background: value noise at three scales around the mean grey.
  cv::Mat base(H, W, CV_32F, cv::Scalar(mean));
  addValueNoise(base, 1.2 * texelsPerUnit, 40.0, rng);
  addValueNoise(base, 0.35 * texelsPerUnit, 25.0, rng);
  addValueNoise(base, 0.08 * texelsPerUnit, 10.0, rng);
  cv::Mat img;
  base.convertTo(img, CV_8U);

  // 2. Shapes, largest first so that small ones stay visible on top of large ones.
  const double area = width * height;
  const int n = static_cast<int>(std::lround(area * shapesPerUnit2 * densityMul));
  const double maxSize = std::min(0.4, 0.9 * std::max(width, height));
  std::vector<TShape> shapes(static_cast<std::size_t>(n));
  for (auto& s : shapes)
  {
    s.size = rng.logUniform(0.04, std::max(0.041, maxSize));
    s.kind = rng.uniformInt(0, 99);
  }
  std::stable_sort(shapes.begin(), shapes.end(), [](const TShape& a, const TShape& b) { return a.size > b.size; });
  const double tpu = texelsPerUnit;
  for (const auto& s : shapes) drawShape(img, s, tpu, mean, contrast, rng);

  // 3. Fine grain (per-texel) and a mid-scale modulation, so that flat regions are not flat.
  cv::Mat f;
  img.convertTo(f, CV_32F);
  addValueNoise(f, 0.03 * texelsPerUnit, 6.0, rng);
  for (int y = 0; y < H; ++y)
  {
    float* row = f.ptr<float>(y);
    for (int x = 0; x < W; ++x) row[x] += static_cast<float>(rng.uniform(-4.0, 4.0));
  }
  f.convertTo(img, CV_8U);  // saturating, rounded

  // 4. Mip-maps (Gaussian pyramid).
  tex.m_levels.push_back(img);
  while (std::min(tex.m_levels.back().cols, tex.m_levels.back().rows) > 4 && tex.m_levels.size() < 12)
  {
    cv::Mat down;
    cv::pyrDown(tex.m_levels.back(), down);
    tex.m_levels.push_back(down);
  }
  tex.buildViews();
  return tex;
}

void CTexture::buildViews()
{
  m_lv.clear();
  for (std::size_t l = 0; l < m_levels.size(); ++l)
  {
    const cv::Mat& m = m_levels[l];
    TLevel v;
    v.data = m.ptr<std::uint8_t>(0);
    v.stride = m.step[0];
    v.w = m.cols;
    v.h = m.rows;
    v.xmax = static_cast<float>(m.cols - 1);
    v.ymax = static_cast<float>(m.rows - 1);
    v.scale = static_cast<float>(m_tpu / static_cast<double>(1u << l));
    m_lv.push_back(v);
  }
}
}  // namespace immslam::sim
