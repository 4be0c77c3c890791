/* imm-monoslam — corner detection in the empty cells of a grid (FAST + normalized Shi-Tomasi). */
#include <immslam/frontend/frontend.h>

#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace immslam::frontend
{
namespace
{
/** Guards the normalization of flat windows (grey levels^2). */
constexpr double kVarianceGuard = 1.0;

struct TCandidate
{
  int u, v, cell;
  double score;
};

void requireGrey(const cv::Mat& grey, const char* where)
{
  if (grey.empty() || grey.type() != CV_8UC1)
    throw std::runtime_error(std::string(where) +
                             ": expected a non-empty 8-bit single-channel (CV_8UC1) image");
}

/** Cell index of an in-image position. */
int cellOf(double u, double v, int W, int H, int cols, int rows)
{
  const int cx = std::min(cols - 1, static_cast<int>(u * cols / W));
  const int cy = std::min(rows - 1, static_cast<int>(v * rows / H));
  return cy * cols + cx;
}

/** The score without bounds checks (the caller guarantees the window + 1 px fits). */
double shiTomasiUnchecked(const cv::Mat& grey, int u, int v, int hw)
{
  std::int64_t sxx = 0, syy = 0, sxy = 0, s = 0, s2 = 0;
  for (int dy = -hw; dy <= hw; ++dy)
  {
    const std::uint8_t* rm = grey.ptr<std::uint8_t>(v + dy - 1);
    const std::uint8_t* r = grey.ptr<std::uint8_t>(v + dy);
    const std::uint8_t* rp = grey.ptr<std::uint8_t>(v + dy + 1);
    for (int x = u - hw; x <= u + hw; ++x)
    {
      const int gx = int(r[x + 1]) - int(r[x - 1]);  // 2 dI/du
      const int gy = int(rp[x]) - int(rm[x]);        // 2 dI/dv
      sxx += gx * gx;
      syy += gy * gy;
      sxy += gx * gy;
      s += r[x];
      s2 += int(r[x]) * int(r[x]);
    }
  }
  const double n = double((2 * hw + 1) * (2 * hw + 1));
  // Mean structure tensor in (grey levels / px)^2: the central differences are 2x the derivative.
  const double a = sxx / (4 * n), b = sxy / (4 * n), c = syy / (4 * n);
  const double lmin = 0.5 * (a + c) - std::sqrt(0.25 * (a - c) * (a - c) + b * b);
  const double var = (double(s2) - double(s) * double(s) / n) / n;
  return std::max(lmin, 0.0) / (std::max(var, 0.0) + kVarianceGuard);
}
}  // namespace

double normalizedShiTomasi(const cv::Mat& grey, int u, int v, int halfWindow)
{
  requireGrey(grey, "frontend::normalizedShiTomasi");
  if (halfWindow < 1) throw std::runtime_error("frontend::normalizedShiTomasi: halfWindow < 1");
  const int m = halfWindow + 1;
  if (u < m || v < m || u >= grey.cols - m || v >= grey.rows - m) return 0.0;
  return shiTomasiUnchecked(grey, u, v, halfWindow);
}

std::vector<TCorner> detectInEmptyCells(const cv::Mat& grey, const std::vector<Vec2>& occupied,
                                        int maxNew, const TDetectorParams& p)
{
  requireGrey(grey, "frontend::detectInEmptyCells");
  if (p.gridCols < 1 || p.gridRows < 1)
    throw std::runtime_error("frontend::detectInEmptyCells: gridCols and gridRows must be >= 1");
  if (p.shiTomasiHalfWindow < 1)
    throw std::runtime_error("frontend::detectInEmptyCells: shiTomasiHalfWindow must be >= 1");
  if (!p.validMask.empty() && (p.validMask.type() != CV_8UC1 || p.validMask.size() != grey.size()))
    throw std::runtime_error("frontend::detectInEmptyCells: validMask must be empty or a CV_8UC1 image of the image's size");
  std::vector<TCorner> out;
  if (maxNew <= 0) return out;

  const int W = grey.cols, H = grey.rows, cols = p.gridCols, rows = p.gridRows;
  std::vector<char> cellBusy(static_cast<size_t>(cols * rows), 0);
  for (const Vec2& o : occupied)
    if (o.allFinite() && o.x() >= 0 && o.y() >= 0 && o.x() < W && o.y() < H)
      cellBusy[cellOf(o.x(), o.y(), W, H, cols, rows)] = 1;
  if (std::find(cellBusy.begin(), cellBusy.end(), 0) == cellBusy.end()) return out;

  std::vector<cv::KeyPoint> kps;
  cv::FAST(grey, kps, p.fastThreshold, true);

  const int hw = p.shiTomasiHalfWindow;
  const int border = std::max(p.borderPx, hw + 1);
  const double minD2 = p.minDistancePx * p.minDistancePx;
  std::vector<TCandidate> cands;
  cands.reserve(kps.size());
  for (const cv::KeyPoint& kp : kps)
  {
    const int u = cvRound(kp.pt.x), v = cvRound(kp.pt.y);
    if (u < border || v < border || u > W - 1 - border || v > H - 1 - border) continue;
    const int cell = cellOf(u, v, W, H, cols, rows);
    if (cellBusy[cell]) continue;
    if (!p.validMask.empty() && !p.validMask.at<std::uint8_t>(v, u)) continue;
    bool nearOccupied = false;
    for (const Vec2& o : occupied)
    {
      const double du = o.x() - u, dv = o.y() - v;
      if (du * du + dv * dv < minD2)
      {
        nearOccupied = true;
        break;
      }
    }
    if (nearOccupied) continue;
    const double s = shiTomasiUnchecked(grey, u, v, hw);
    if (s < p.minShiTomasi) continue;
    cands.push_back({u, v, cell, s});
  }

  // Strongest first; position breaks ties so the result never depends on the input order.
  std::sort(cands.begin(), cands.end(),
            [](const TCandidate& a, const TCandidate& b)
            {
              if (a.score != b.score) return a.score > b.score;
              if (a.v != b.v) return a.v < b.v;
              return a.u < b.u;
            });

  // Greedy: one per empty cell, mutual distance >= minDistancePx.
  std::vector<char> cellTaken(cellBusy.size(), 0);
  for (const TCandidate& c : cands)
  {
    if (cellTaken[c.cell]) continue;
    bool tooClose = false;
    for (const TCorner& k : out)
    {
      const double du = k.uv.x() - c.u, dv = k.uv.y() - c.v;
      if (du * du + dv * dv < minD2)
      {
        tooClose = true;
        break;
      }
    }
    if (tooClose) continue;
    cellTaken[c.cell] = 1;
    out.push_back({Vec2(c.u, c.v), c.score});
    if (static_cast<int>(out.size()) >= maxNew) break;
  }
  return out;
}
cv::Mat lensMask(const camera::CCameraModel& cam, int margin)
{
  const int W = cam.width(), H = cam.height();
  const auto imaged = [&](int u, int v) { return cam.imagesPixel(Vec2(u, v)); };
  // The models' limits are radii about a principal point inside the image (a fold, 90 degrees): when
  // the whole border is imaged so is the inside, and the per-pixel pass is skipped.
  bool borderImaged = true;
  for (int u = 0; u < W && borderImaged; ++u) borderImaged = imaged(u, 0) && imaged(u, H - 1);
  for (int v = 0; v < H && borderImaged; ++v) borderImaged = imaged(0, v) && imaged(W - 1, v);
  if (borderImaged) return cv::Mat();
  cv::Mat mask(H, W, CV_8UC1);
  for (int v = 0; v < H; ++v)
  {
    auto* row = mask.ptr<std::uint8_t>(v);
    for (int u = 0; u < W; ++u) row[u] = imaged(u, v) ? 255 : 0;
  }
  if (margin > 0)
    cv::erode(mask, mask, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * margin + 1, 2 * margin + 1)),
              cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(255));
  return mask;
}

cv::Mat growExclusion(const cv::Mat& excluded, int radius)
{
  if (excluded.empty()) return cv::Mat();
  if (excluded.type() != CV_8UC1 || radius < 0)
    throw std::invalid_argument("frontend::growExclusion: need a CV_8UC1 mask and radius >= 0");
  cv::Mat grown;
  cv::dilate(excluded != 0, grown, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * radius + 1, 2 * radius + 1)));
  return grown;
}

bool maskedAt(const cv::Mat& mask, const Vec2& uv)
{
  if (mask.empty() || !uv.allFinite()) return false;
  const double u = std::round(uv.x()), v = std::round(uv.y());
  return u >= 0 && v >= 0 && u < mask.cols && v < mask.rows &&
         mask.at<std::uint8_t>(static_cast<int>(v), static_cast<int>(u)) != 0;
}
}  // namespace immslam::frontend
