/* imm-monoslam — ray-casting renderer (see CRenderer.h). */
#include <immslam/math/quaternion.h>
#include <immslam/sim/CRandom.h>
#include <immslam/sim/CRenderer.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <thread>

namespace immslam::sim
{
namespace
{
constexpr int kTile = 16;

/** Runs f(row_begin, row_end) over [0, rows) split into `threads` contiguous blocks. */
template <class F>
void parallelRows(int rows, int threads, const F& f)
{
  threads = std::max(1, std::min(threads, rows));
  if (threads == 1)
  {
    f(0, rows);
    return;
  }
  std::vector<std::thread> pool;
  pool.reserve(static_cast<std::size_t>(threads - 1));
  for (int i = 1; i < threads; ++i)
    pool.emplace_back([&f, i, rows, threads] { f(rows * i / threads, rows * (i + 1) / threads); });
  f(0, rows / threads);
  for (auto& t : pool) t.join();
}

std::uint8_t quantize(float x)
{
  const float r = std::floor(x + 0.5f);
  return static_cast<std::uint8_t>(r < 0.f ? 0.f : (r > 255.f ? 255.f : r));
}

double angleBetween(const Vec3& a, const Vec3& b) { return std::atan2(a.cross(b).norm(), a.dot(b)); }

/** The standard normal quantiles at (i + 1/2) / n, i = 0..n-1 (bisection on erfc): pixel noise is
 * drawn by indexing this table with random bits, much faster than Box-Muller. */
std::vector<float> normalQuantiles(int n)
{
  std::vector<float> t(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i)
  {
    const double p = (i + 0.5) / n;
    double lo = -10, hi = 10;
    for (int it = 0; it < 80; ++it)
    {
      const double mid = 0.5 * (lo + hi);
      (0.5 * std::erfc(-mid / std::sqrt(2.0)) < p ? lo : hi) = mid;
    }
    t[static_cast<std::size_t>(i)] = static_cast<float>(0.5 * (lo + hi));
  }
  return t;
}
constexpr int kNoiseBits = 12;
}  // namespace

struct CRenderer::TInstance
{
  Mat3 R_BC;
  Vec3 o_B;  ///< optical centre in the box frame
  Vec3 half;
  Vec3 sphere_C;  ///< box centre in the camera frame
  double radius = 0;
  int objectId = 0;
  bool moving = false;
  int firstSurface = 0;
  bool inside = false;
};

struct CRenderer::THit
{
  int inst = -1;
  int axis = 0;
  bool positive = false;
  double t = 0;
  Vec3 p_B;
  double cosInc = 1;
};

CRenderer::CRenderer(camera::CCameraModel::Ptr cam, int threads)
    : m_cam(std::move(cam)), m_noiseTable(normalQuantiles(1 << kNoiseBits))
{
  if (!m_cam) throw std::runtime_error("CRenderer: null camera model");
  m_w = m_cam->width();
  m_h = m_cam->height();
  if (m_w < 2 || m_h < 2 || m_w > 16384 || m_h > 16384)
    throw std::runtime_error("CRenderer: unsupported image size " + std::to_string(m_w) + "x" + std::to_string(m_h));
  m_threads = threads > 0 ? threads : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  const std::size_t n = static_cast<std::size_t>(m_w) * m_h;
  m_bearings.resize(n);
  m_alpha.resize(n);
  m_valid.resize(n);
  parallelRows(m_h, m_threads, [&](int y0, int y1) {
    for (int v = y0; v < y1; ++v)
      for (int u = 0; u < m_w; ++u)
      {
        const std::size_t i = static_cast<std::size_t>(v) * m_w + u;
        // A pixel outside what the lens images (a fisheye's corners beyond its image circle, beyond a
        // distortion's fold) is black, as in a real camera.
        Vec3 b;
        m_valid[i] = m_cam->imagesPixel(Vec2(u, v), &b);
        m_bearings[i] = m_valid[i] ? b : Vec3(0, 0, 1);
      }
  });
  // Pixel angular size: geometric mean of the angles to the horizontal and vertical neighbours.
  for (int v = 0; v < m_h; ++v)
    for (int u = 0; u < m_w; ++u)
    {
      const int u0 = std::max(0, u - 1), u1 = std::min(m_w - 1, u + 1);
      const int v0 = std::max(0, v - 1), v1 = std::min(m_h - 1, v + 1);
      const double au = angleBetween(bearing(u0, v), bearing(u1, v)) / (u1 - u0);
      const double av = angleBetween(bearing(u, v0), bearing(u, v1)) / (v1 - v0);
      m_alpha[static_cast<std::size_t>(v) * m_w + u] = std::sqrt(au * av);
    }
  // Tile cones: axis = normalized mean bearing, half-angle = largest angle to a bearing of the tile.
  m_tilesX = (m_w + kTile - 1) / kTile;
  m_tilesY = (m_h + kTile - 1) / kTile;
  m_tileAxis.resize(static_cast<std::size_t>(m_tilesX) * m_tilesY);
  m_tileHalfAngle.resize(m_tileAxis.size());
  for (int ty = 0; ty < m_tilesY; ++ty)
    for (int tx = 0; tx < m_tilesX; ++tx)
    {
      const int ue = std::min(m_w, (tx + 1) * kTile), ve = std::min(m_h, (ty + 1) * kTile);
      Vec3 sum = Vec3::Zero();
      for (int v = ty * kTile; v < ve; ++v)
        for (int u = tx * kTile; u < ue; ++u) sum += bearing(u, v);
      const Vec3 axis = sum.normalized();
      double ha = 0;
      for (int v = ty * kTile; v < ve; ++v)
        for (int u = tx * kTile; u < ue; ++u) ha = std::max(ha, angleBetween(axis, bearing(u, v)));
      const std::size_t i = static_cast<std::size_t>(ty) * m_tilesX + tx;
      m_tileAxis[i] = axis;
      m_tileHalfAngle[i] = ha + 1e-6;
    }
}

std::vector<CRenderer::TInstance> CRenderer::prepare(const std::vector<TBox>& boxes, const TPose& T_W_C) const
{
  if (boxes.empty() || !boxes.front().inside) throw std::runtime_error("CRenderer: the first box must be the room");
  if (boxes.size() > 64) throw std::runtime_error("CRenderer: at most 63 boxes besides the room");
  const Mat3 R_WC = math::quatToRotation(T_W_C.q);
  std::vector<TInstance> out(boxes.size());
  for (std::size_t i = 0; i < boxes.size(); ++i)
  {
    const TBox& b = boxes[i];
    TInstance& I = out[i];
    const Mat3 R_WB = math::quatToRotation(b.T_W_B.q);
    I.R_BC = R_WB.transpose() * R_WC;
    I.o_B = R_WB.transpose() * (T_W_C.t - b.T_W_B.t);
    I.half = b.half;
    I.sphere_C = R_WC.transpose() * (b.T_W_B.t - T_W_C.t);
    I.radius = b.half.norm() * (1.0 + 1e-9) + 1e-9;
    I.objectId = b.objectId;
    I.moving = b.moving;
    I.firstSurface = b.firstSurface;
    I.inside = b.inside;
  }
  return out;
}

bool CRenderer::intersect(const std::vector<TInstance>& inst, std::uint64_t candidates, const Vec3& b_C, THit& hit)
{
  double best = std::numeric_limits<double>::infinity();
  hit.inst = -1;
  while (candidates)
  {
    const int i = __builtin_ctzll(candidates);
    candidates &= candidates - 1;
    const TInstance& I = inst[static_cast<std::size_t>(i)];
    const Vec3 d = I.R_BC * b_C;
    double tnear = -std::numeric_limits<double>::infinity(), tfar = std::numeric_limits<double>::infinity();
    int axis = -1;
    bool miss = false;
    for (int a = 0; a < 3; ++a)
    {
      if (std::abs(d[a]) < 1e-15)
      {
        if (std::abs(I.o_B[a]) > I.half[a]) miss = true;
        continue;
      }
      const double inv = 1.0 / d[a];
      double t1 = (-I.half[a] - I.o_B[a]) * inv, t2 = (I.half[a] - I.o_B[a]) * inv;
      if (t1 > t2) std::swap(t1, t2);
      if (t1 > tnear)
      {
        tnear = t1;
        axis = a;
      }
      if (t2 < tfar) tfar = t2;
    }
    if (miss || axis < 0 || tnear > tfar || tnear <= 1e-9 || tnear >= best) continue;
    best = tnear;
    hit.inst = i;
    hit.axis = axis;
    hit.positive = d[axis] < 0;  // entering through the + face
    hit.t = tnear;
    hit.p_B = I.o_B + tnear * d;
    hit.cosInc = std::abs(d[axis]);
  }
  if (hit.inst >= 0) return true;
  // The room, seen from inside: the nearest exit plane.
  const TInstance& R = inst[0];
  const Vec3 d = R.R_BC * b_C;
  double tmin = std::numeric_limits<double>::infinity();
  int axis = -1;
  for (int a = 0; a < 3; ++a)
  {
    if (std::abs(d[a]) < 1e-15) continue;
    const double t = ((d[a] > 0 ? R.half[a] : -R.half[a]) - R.o_B[a]) / d[a];
    if (t < tmin)
    {
      tmin = t;
      axis = a;
    }
  }
  if (axis < 0 || !(tmin > 0)) return false;
  hit.inst = 0;
  hit.axis = axis;
  hit.positive = d[axis] > 0;
  hit.t = tmin;
  hit.p_B = R.o_B + tmin * d;
  hit.cosInc = std::abs(d[axis]);
  return true;
}

std::optional<TRayHit> CRenderer::raycast(const std::vector<TBox>& boxes, const TPose& T_W_C, const Vec2& uv) const
{
  const Vec3 b = m_cam->unproject(uv).unitVector();
  if (!b.allFinite() || !(b.z() > 0)) return std::nullopt;
  const auto inst = prepare(boxes, T_W_C);
  const std::uint64_t all = inst.size() >= 64 ? ~1ULL : (((1ULL << inst.size()) - 1) & ~1ULL);
  THit h;
  if (!intersect(inst, all, b, h)) return std::nullopt;
  TRayHit r;
  const auto& I = inst[static_cast<std::size_t>(h.inst)];
  r.objectId = I.objectId;
  r.moving = I.moving;
  r.surfaceId = I.firstSurface + 2 * h.axis + (h.positive ? 1 : 0);
  r.range = h.t;
  r.depth = h.t * b.z();
  r.p_W = T_W_C.t + math::quatRotate(T_W_C.q, h.t * b);
  return r;
}

std::vector<std::uint64_t> CRenderer::tileCandidates(const std::vector<TInstance>& inst) const
{
  std::vector<std::uint64_t> tileBits(m_tileAxis.size(), 0);
  for (std::size_t t = 0; t < tileBits.size(); ++t)
    for (std::size_t i = 1; i < inst.size(); ++i)
    {
      const auto& I = inst[i];
      const double dist = I.sphere_C.norm();
      bool cand = dist <= I.radius;
      if (!cand)
        cand = angleBetween(m_tileAxis[t], I.sphere_C) <= m_tileHalfAngle[t] + std::asin(I.radius / dist) + 1e-6;
      if (cand) tileBits[t] |= 1ULL << i;
    }
  return tileBits;
}

cv::Mat CRenderer::quantized(const cv::Mat& value, bool colour, const TRenderOptions& opts) const
{
  const int ch = colour ? 3 : 1;
  cv::Mat img(m_h, m_w, colour ? CV_8UC3 : CV_8UC1);
  parallelRows(m_h, m_threads, [&](int y0, int y1) {
    for (int v = y0; v < y1; ++v)
    {
      const float* vrow = value.ptr<float>(v);
      std::uint8_t* orow = img.ptr<std::uint8_t>(v);
      if (opts.noise_sigma_grey > 0)
      {
        CRandom rng(CRandom::streamSeed(opts.noise_seed, "pixel-noise-row", static_cast<std::uint64_t>(v)));
        const float sigma = static_cast<float>(opts.noise_sigma_grey);
        std::uint64_t bits = 0;
        int left = 0;
        for (int i = 0; i < m_w * ch; ++i)
        {
          if (left == 0)
          {
            bits = rng.next();
            left = 64 / kNoiseBits;
          }
          const float n = m_noiseTable[bits & ((1u << kNoiseBits) - 1)];
          bits >>= kNoiseBits;
          --left;
          orow[i] = quantize(vrow[i] + sigma * n);
        }
      }
      else
        for (int i = 0; i < m_w * ch; ++i) orow[i] = quantize(vrow[i]);
    }
  });
  return img;
}

TRenderedImages CRenderer::render(const CWorld& world, const std::vector<TBox>& boxes, const TPose& T_W_C,
                                  const TRenderOptions& opts) const
{
  const auto inst = prepare(boxes, T_W_C);
  const auto& surfaces = world.surfaces();
  for (const auto& I : inst)
    if (I.firstSurface < 0 || I.firstSurface + 6 > static_cast<int>(surfaces.size()))
      throw std::runtime_error("CRenderer: box surfaces out of range");

  const std::vector<std::uint64_t> tileBits = tileCandidates(inst);

  TRenderedImages out;
  out.mask.create(m_h, m_w, CV_8UC1);
  if (opts.depth) out.depth.create(m_h, m_w, CV_32FC1);
  const bool shade = !opts.mask_only;
  const bool colour = shade && opts.colour;
  cv::Mat value;  // linear radiance before blur/noise
  if (shade) value.create(m_h, m_w, colour ? CV_32FC3 : CV_32FC1);

  parallelRows(m_h, m_threads, [&](int y0, int y1) {
    THit h;
    for (int v = y0; v < y1; ++v)
    {
      std::uint8_t* mrow = out.mask.ptr<std::uint8_t>(v);
      float* drow = opts.depth ? out.depth.ptr<float>(v) : nullptr;
      float* vrow = shade ? value.ptr<float>(v) : nullptr;
      const std::size_t tileRow = static_cast<std::size_t>(v / kTile) * m_tilesX;
      for (int u = 0; u < m_w; ++u)
      {
        const std::size_t pi = static_cast<std::size_t>(v) * m_w + u;
        const Vec3& b = m_bearings[pi];
        const bool ok = m_valid[pi] && intersect(inst, tileBits[tileRow + u / kTile], b, h);
        if (!ok)
        {
          mrow[u] = 0;
          if (drow) drow[u] = 0.f;
          if (vrow)
            for (int c = 0; c < (colour ? 3 : 1); ++c) vrow[(colour ? 3 : 1) * u + c] = 0.f;
          continue;
        }
        const auto& I = inst[static_cast<std::size_t>(h.inst)];
        mrow[u] = static_cast<std::uint8_t>(I.moving ? I.objectId : 0);  // masks: what moves now
        if (drow) drow[u] = static_cast<float>(h.t * b.z());
        if (!vrow) continue;
        const int a = h.axis, j = (a + 1) % 3, k = (a + 2) % 3;
        const TSurface& S = surfaces[static_cast<std::size_t>(I.firstSurface + 2 * a + (h.positive ? 1 : 0))];
        const double footprint = h.t * m_alpha[pi] / std::sqrt(std::max(h.cosInc, 0.05));
        const float g = S.texture.sample(h.p_B[j] + I.half[j], h.p_B[k] + I.half[k], footprint) * S.gain;
        if (colour)
          for (int c = 0; c < 3; ++c) vrow[3 * u + c] = g * S.tint[static_cast<std::size_t>(c)];
        else
          vrow[u] = g;
      }
    }
  });
  if (!shade) return out;

  if (opts.blur_sigma_px > 0) cv::GaussianBlur(value, value, cv::Size(0, 0), opts.blur_sigma_px, 0, cv::BORDER_REFLECT);

  const cv::Mat img = quantized(value, colour, opts);
  if (colour)
  {
    out.colour = img;
    cv::cvtColor(img, out.grey, cv::COLOR_BGR2GRAY);
  }
  else
    out.grey = img;
  return out;
}
}  // namespace immslam::sim
