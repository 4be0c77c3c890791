/* imm-monoslam — per-frame overlays: gate ellipses, matches, feature classes, legend, text. */
#include <immslam/viz/overlay.h>

#include "cv_text.h"

#include <Eigen/Dense>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace immslam::viz
{
namespace
{
constexpr int kShift = 4;  // sub-pixel bits of cv drawing calls
constexpr double kOne = 1 << kShift;

cv::Point fixedPoint(const Vec2& p)
{
  return cv::Point(static_cast<int>(std::lround(p.x() * kOne)),
      static_cast<int>(std::lround(p.y() * kOne)));
}

cv::Mat toBgr8(const cv::Mat& image)
{
  if (image.empty()) throw std::runtime_error("viz::drawOverlay: empty image");
  cv::Mat img8;
  switch (image.depth())
  {
    case CV_8U: img8 = image; break;
    case CV_16U: image.convertTo(img8, CV_8U, 1.0 / 256.0); break;
    case CV_32F:
    case CV_64F: image.convertTo(img8, CV_8U, 255.0); break;
    default: throw std::runtime_error("viz::drawOverlay: unsupported image depth " +
                                      std::to_string(image.depth()));
  }
  cv::Mat out;
  switch (img8.channels())
  {
    case 1: cv::cvtColor(img8, out, cv::COLOR_GRAY2BGR); break;
    case 3: out = img8.clone(); break;
    case 4: cv::cvtColor(img8, out, cv::COLOR_BGRA2BGR); break;
    default: throw std::runtime_error("viz::drawOverlay: unsupported channel count " +
                                      std::to_string(img8.channels()));
  }
  return out;
}

cv::Scalar statusColour(ESearchStatus s, const TOverlayStyle& st)
{
  switch (s)
  {
    case ESearchStatus::Inlier: return toBgr(st.inlierColour);
    case ESearchStatus::Rescued: return toBgr(st.rescuedColour);
    case ESearchStatus::Rejected: return toBgr(st.rejectedColour);
    case ESearchStatus::NotFound: break;
  }
  return toBgr(st.notFoundColour);
}

cv::Scalar classColour(EFeatureClass c, const TOverlayStyle& st)
{
  switch (c)
  {
    case EFeatureClass::Static: return toBgr(st.staticColour);
    case EFeatureClass::Dynamic: return toBgr(st.dynamicColour);
    case EFeatureClass::Pending: break;
  }
  return toBgr(st.pendingColour);
}

void drawCross(cv::Mat& img, const Vec2& p, double r, const cv::Scalar& col, int th, bool diagonal)
{
  const Vec2 a = diagonal ? Vec2(r, r) : Vec2(r, 0), b = diagonal ? Vec2(r, -r) : Vec2(0, r);
  cv::line(img, fixedPoint(p - a), fixedPoint(p + a), col, th, cv::LINE_AA, kShift);
  cv::line(img, fixedPoint(p - b), fixedPoint(p + b), col, th, cv::LINE_AA, kShift);
}

void drawMarker(cv::Mat& img, const Vec2& p, double r, const cv::Scalar& col)
{
  cv::circle(img, fixedPoint(p), static_cast<int>(std::lround((r + 1) * kOne)),
      cv::Scalar(0, 0, 0), cv::FILLED, cv::LINE_AA, kShift);
  cv::circle(img, fixedPoint(p), static_cast<int>(std::lround(r * kOne)), col, cv::FILLED,
      cv::LINE_AA, kShift);
}

struct TLegendEntry
{
  std::string label;
  cv::Scalar colour;
  bool isFeature;
};

/** Top-left corner of a w x h box placed in a corner with a 6 px gap. */
cv::Point cornerOrigin(const cv::Mat& img, ECorner c, int w, int h)
{
  const int gap = 6;
  const bool right = c == ECorner::TopRight || c == ECorner::BottomRight;
  const bool bottom = c == ECorner::BottomLeft || c == ECorner::BottomRight;
  return cv::Point(right ? img.cols - w - gap : gap, bottom ? img.rows - h - gap : gap);
}

void drawLegend(cv::Mat& img, const std::vector<TLegendEntry>& entries, const TOverlayStyle& st)
{
  if (entries.empty()) return;
  const double fs = st.fontScale;
  int base = 0;
  const int th = textSize("Ag", fs, 1, &base).height + base;
  const int rowH = std::max(th + 4, int(2 * st.markerRadius) + 6);
  const int icon = std::max(14, int(3 * st.markerRadius));
  int w = 0;
  for (const auto& e : entries) w = std::max(w, textSize(e.label, fs, 1).width);
  const int pad = 6;
  const int boxW = pad * 3 + icon + w, boxH = pad * 2 + rowH * int(entries.size());
  const cv::Rect box(cornerOrigin(img, st.legendCorner, boxW, boxH), cv::Size(boxW, boxH));
  blendRect(img, box, cv::Scalar(0, 0, 0), 0.6);
  for (size_t i = 0; i < entries.size(); ++i)
  {
    const int y = box.y + pad + int(i) * rowH;
    const Vec2 c(box.x + pad + 0.5 * icon, y + 0.5 * rowH);
    if (entries[i].isFeature)
      drawMarker(img, c, st.markerRadius, entries[i].colour);
    else
      cv::ellipse(img, fixedPoint(c),
          cv::Size(int(0.5 * icon * kOne), int(0.3 * rowH * kOne)), 0, 0, 360, entries[i].colour,
          st.lineThickness, cv::LINE_AA, kShift);
    drawText(img, entries[i].label, cv::Point(box.x + 2 * pad + icon, y + (rowH - th) / 2 + 1), fs,
        cv::Scalar(255, 255, 255), 1);
  }
}
}  // namespace

std::vector<Vec2> gateEllipsePolygon(const Vec2& h, const Mat2& S, double chi2, int n)
{
  std::vector<Vec2> out;
  if (!(chi2 > 0) || !std::isfinite(chi2) || !S.allFinite() || !h.allFinite() || n < 3) return out;
  const Eigen::LLT<Mat2> llt(0.5 * (S + S.transpose()));
  if (llt.info() != Eigen::Success) return out;
  const Mat2 L = llt.matrixL();
  if (!(L(0, 0) > 0 && L(1, 1) > 0)) return out;
  const double r = std::sqrt(chi2);
  out.reserve(n);
  for (int i = 0; i < n; ++i)
  {
    const double t = 2.0 * M_PI * i / n;
    out.push_back(h + r * L * Vec2(std::cos(t), std::sin(t)));
  }
  return out;
}

double gateEllipseArea(const Mat2& S, double chi2)
{
  const double d = S.determinant();
  return d > 0 ? M_PI * chi2 * std::sqrt(d) : 0.0;
}

int overlayScale(const cv::Size& size, const TOverlayStyle& style)
{
  if (style.upscale > 0) return style.upscale;
  return std::max(size.width, size.height) <= 400 ? 2 : 1;
}

namespace
{
/** One search of the overlay at scale s: its gate ellipse, the predicted point, the match (a cross
 * when rejected) and the line to it, the feature's id. */
void drawSearch(cv::Mat& out, const TSearchView& sv, const TOverlayStyle& st, int s)
{
  const cv::Scalar col = statusColour(sv.status, st);
  const int th = std::max(1, st.lineThickness);
  const double r = st.markerRadius;
  const auto poly = gateEllipsePolygon(sv.h, sv.S, sv.gateChi2, std::max(8, st.ellipseSegments));
  if (!poly.empty())
  {
    std::vector<cv::Point> pts;
    pts.reserve(poly.size());
    for (const auto& p : poly) pts.push_back(fixedPoint(toOverlayPixel(p, s)));
    cv::polylines(out, pts, true, col, th, cv::LINE_AA, kShift);
  }
  if (!sv.h.allFinite()) return;
  const Vec2 h = toOverlayPixel(sv.h, s);
  drawCross(out, h, 0.6 * r, col, th, false);
  if (sv.z && sv.z->allFinite())
  {
    const Vec2 z = toOverlayPixel(*sv.z, s);
    if (st.drawMatchLines) cv::line(out, fixedPoint(h), fixedPoint(z), col, th, cv::LINE_AA, kShift);
    if (sv.status == ESearchStatus::Rejected)
      drawCross(out, z, r, col, th + 1, true);
    else
      cv::circle(out, fixedPoint(z), static_cast<int>(std::lround(r * kOne)), col, th,
          cv::LINE_AA, kShift);
  }
  if (st.drawIds && sv.id >= 0)
    drawText(out, std::to_string(sv.id), cv::Point(int(h.x() + r + 2), int(h.y() + 2)),
        0.8 * st.fontScale, col, 1);
}
}  // namespace

cv::Mat drawOverlay(const cv::Mat& image, const TOverlayContent& content, const TOverlayStyle& style)
{
  cv::Mat out = toBgr8(image);
  const int s = overlayScale(out.size(), style);
  if (s > 1) cv::resize(out, out, cv::Size(), s, s, cv::INTER_NEAREST);
  // Sizes grow with outputs wider than 640 px.
  TOverlayStyle st = style;
  const double grow = std::max(1.0, out.cols / 640.0);
  st.lineThickness = static_cast<int>(std::lround(std::max(1, style.lineThickness) * grow));
  st.markerRadius = style.markerRadius * grow;
  st.fontScale = style.fontScale * grow;
  const double r = st.markerRadius;

  bool used[4] = {false, false, false, false};
  for (const auto& sv : content.searches)
  {
    used[static_cast<int>(sv.status)] = true;
    drawSearch(out, sv, st, s);
  }

  bool usedCls[3] = {false, false, false};
  for (const auto& f : content.features)
  {
    if (!f.uv.allFinite()) continue;
    usedCls[static_cast<int>(f.cls)] = true;
    const Vec2 p = toOverlayPixel(f.uv, s);
    drawMarker(out, p, r, classColour(f.cls, st));
    if (st.drawIds && f.id >= 0)
      drawText(out, std::to_string(f.id), cv::Point(int(p.x() + r + 2), int(p.y() + 2)),
          0.8 * st.fontScale, classColour(f.cls, st), 1);
  }

  if (!content.textLines.empty())
  {
    // Measure on a scratch image, then place in the requested corner.
    cv::Mat scratch(1, 1, CV_8UC3);
    const cv::Rect measured = drawTextBox(scratch, content.textLines, cv::Point(0, 0), st.fontScale,
        cv::Scalar(255, 255, 255), cv::Scalar(0, 0, 0), 0.6);
    drawTextBox(out, content.textLines, cornerOrigin(out, st.textCorner, measured.width, measured.height),
        st.fontScale, cv::Scalar(255, 255, 255), cv::Scalar(0, 0, 0), 0.6);
  }

  if (st.drawLegend)
  {
    std::vector<TLegendEntry> e;
    const bool all = st.legendAllEntries;
    if (all || usedCls[0]) e.push_back({"static", classColour(EFeatureClass::Static, st), true});
    if (all || usedCls[1]) e.push_back({"dynamic", classColour(EFeatureClass::Dynamic, st), true});
    if (all || usedCls[2]) e.push_back({"pending", classColour(EFeatureClass::Pending, st), true});
    const ESearchStatus order[4] = {ESearchStatus::Inlier, ESearchStatus::Rescued,
        ESearchStatus::Rejected, ESearchStatus::NotFound};
    const char* names[4] = {"matched", "rescued", "rejected", "not found"};
    for (int i = 0; i < 4; ++i)
      if (all || used[static_cast<int>(order[i])])
        e.push_back({names[i], statusColour(order[i], st), false});
    drawLegend(out, e, st);
  }
  return out;
}
}  // namespace immslam::viz
