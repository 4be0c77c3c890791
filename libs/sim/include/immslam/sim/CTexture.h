/* imm-monoslam — procedural, deterministic, corner-rich grey textures with mip-maps. */
#pragma once

#include <opencv2/core/mat.hpp>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

namespace immslam::sim
{
/** A grey texture covering a rectangle of `width x height` units, with a mip-map pyramid for
 * anti-aliased (trilinear) look-ups.
 *
 * The content is generated from a seed: value noise at three scales, then many random shapes drawn
 * largest first (filled and hollow rectangles, rotated rectangles, small checkerboards, triangles and
 * quadrilaterals, ellipses) of random grey levels (around a per-surface mean and contrast; the density
 * also varies per surface) and sizes log-uniform in 4 cm ... 40 cm, then a
 * fine grain. Shapes give corners at every scale; nothing repeats, so 11x11 normalized
 * cross-correlation matching behaves as on real images. */
class CTexture
{
 public:
  CTexture() = default;
  CTexture(const CTexture& o) : m_levels(o.m_levels), m_tpu(o.m_tpu) { buildViews(); }
  CTexture(CTexture&& o) : m_levels(std::move(o.m_levels)), m_tpu(o.m_tpu) { buildViews(); }
  CTexture& operator=(const CTexture& o)
  {
    m_levels = o.m_levels;
    m_tpu = o.m_tpu;
    buildViews();
    return *this;
  }
  CTexture& operator=(CTexture&& o)
  {
    m_levels = std::move(o.m_levels);
    m_tpu = o.m_tpu;
    buildViews();
    return *this;
  }

  /** Generates the texture of a `width x height` units face.
   * \param texelsPerUnit resolution of level 0.
   * \param shapesPerUnit2 density of the drawn shapes. */
  static CTexture generate(double width, double height, double texelsPerUnit, double shapesPerUnit2,
                           std::uint64_t seed);

  /** Trilinear look-up of the grey level (0..255) at face coordinates (s, t) (units from the face's
   * corner), for a pixel whose footprint on the face is `footprint` units wide: the mip level is
   * \f$\lambda = \log_2(\text{footprint} \cdot \text{texels per unit})\f$. */
  float sample(double s, double t, double footprint) const
  {
    const float lambda = footprint > 0 ? fastLog2(static_cast<float>(footprint * m_tpu)) : 0.0f;
    const int last = static_cast<int>(m_levels.size()) - 1;
    const float fs = static_cast<float>(s), ft = static_cast<float>(t);
    if (lambda <= 0.0f) return bilinear(0, fs, ft);
    if (lambda >= static_cast<float>(last)) return bilinear(last, fs, ft);
    const int l0 = static_cast<int>(lambda);
    const float f = lambda - static_cast<float>(l0);
    const float a = bilinear(l0, fs, ft), b = bilinear(l0 + 1, fs, ft);
    return a + f * (b - a);
  }

  /** log2(x) for x > 0 within ~0.005 (exponent + quadratic in the mantissa); enough to pick mip levels. */
  static float fastLog2(float x)
  {
    std::uint32_t bits;
    std::memcpy(&bits, &x, sizeof(bits));
    const int e = static_cast<int>((bits >> 23) & 255u) - 128;
    bits = (bits & 0x007FFFFFu) | 0x3F800000u;
    float m;
    std::memcpy(&m, &bits, sizeof(m));
    return static_cast<float>(e) + (-0.34484843f * m + 2.02466578f) * m - 0.67487759f;
  }

  /** Mip level i (CV_8UC1; level 0 is full resolution). */
  const cv::Mat& level(int i) const { return m_levels.at(static_cast<std::size_t>(i)); }
  int levels() const { return static_cast<int>(m_levels.size()); }
  double texelsPerUnit() const { return m_tpu; }

 private:
  float bilinear(int l, float s, float t) const
  {
    const TLevel& L = m_lv[static_cast<std::size_t>(l)];
    float x = s * L.scale - 0.5f, y = t * L.scale - 0.5f;
    x = x < 0.f ? 0.f : (x > L.xmax ? L.xmax : x);
    y = y < 0.f ? 0.f : (y > L.ymax ? L.ymax : y);
    const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
    const int x1 = x0 + (x0 < L.w - 1 ? 1 : 0);
    const std::size_t dy = y0 < L.h - 1 ? L.stride : 0;
    const float fx = x - static_cast<float>(x0), fy = y - static_cast<float>(y0);
    const std::uint8_t* r0 = L.data + static_cast<std::size_t>(y0) * L.stride;
    const std::uint8_t* r1 = r0 + dy;
    const float top = r0[x0] + fx * static_cast<float>(r0[x1] - r0[x0]);
    const float bot = r1[x0] + fx * static_cast<float>(r1[x1] - r1[x0]);
    return top + fy * (bot - top);
  }

  /** Raw view of one level for the hot loop. */
  struct TLevel
  {
    const std::uint8_t* data;
    std::size_t stride;
    int w, h;
    float xmax, ymax, scale;
  };
  void buildViews();

  std::vector<TLevel> m_lv;
  std::vector<cv::Mat> m_levels;
  double m_tpu = 100.0;
};
}  // namespace immslam::sim
