/* imm-monoslam — deterministic PNG plots with OpenCV drawing. */
#include <immslam/viz/CPlot.h>
#include <immslam/viz/overlay.h>

#include "cv_text.h"
#include "plot_axes.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace immslam::viz
{
namespace
{
constexpr int kShift = 4;
constexpr double kOne = 1 << kShift;
constexpr double kTickFont = 0.45, kLabelFont = 0.55, kTitleFont = 0.7, kLegendFont = 0.47;
const cv::Scalar kInk(40, 40, 40), kGridInk(228, 228, 228), kMinorGridInk(242, 242, 242);

using detail::linearAxis;
using detail::logAxis;
using detail::TAxis;

cv::Point fp(double x, double y)
{
  const double lim = 1e5;
  return cv::Point(static_cast<int>(std::lround(std::clamp(x, -lim, lim) * kOne)),
      static_cast<int>(std::lround(std::clamp(y, -lim, lim) * kOne)));
}

void dashedSegment(cv::Mat& roi, cv::Point2d a, cv::Point2d b, const cv::Scalar& c, int w,
    double& phase)
{
  const double on = 9, off = 6, len = std::hypot(b.x - a.x, b.y - a.y);
  if (len <= 0) return;
  double s = 0;
  while (s < len)
  {
    const double period = std::fmod(phase, on + off);
    const bool drawing = period < on;
    const double step = std::min(len - s, drawing ? on - period : on + off - period);
    if (drawing)
    {
      const cv::Point2d p = a + (b - a) * (s / len), q = a + (b - a) * ((s + step) / len);
      cv::line(roi, fp(p.x, p.y), fp(q.x, q.y), c, w, cv::LINE_AA, kShift);
    }
    s += step;
    phase += step;
  }
}

void putRotatedLabel(cv::Mat& img, const std::string& s, cv::Point centre, double scale)
{
  int base = 0;
  const cv::Size sz = textSize(s, scale, 1, &base);
  cv::Mat t(sz.height + base + 4, sz.width + 4, img.type(), cv::Scalar(255, 255, 255));
  drawText(t, s, cv::Point(2, 2), scale, kInk, 1);
  cv::Mat r;
  cv::rotate(t, r, cv::ROTATE_90_COUNTERCLOCKWISE);
  cv::Rect dst(centre.x - r.cols / 2, centre.y - r.rows / 2, r.cols, r.rows);
  dst &= cv::Rect(0, 0, img.cols, img.rows);
  if (dst.empty()) return;
  r(cv::Rect(dst.x - (centre.x - r.cols / 2), dst.y - (centre.y - r.rows / 2), dst.width,
        dst.height))
      .copyTo(img(dst));
}

struct TLegendItem
{
  enum EKind
  {
    Line,
    Box,
    Header
  } kind;
  std::string name;
  cv::Scalar colour;
  int width = 2;
  bool dashed = false;
};
}  // namespace

void writePng(const cv::Mat& img, const std::string& path)
{
  bool ok = false;
  try
  {
    ok = !img.empty() && cv::imwrite(path, img);
  }
  catch (const cv::Exception& e)
  {
    throw std::runtime_error("viz: cannot write " + path + ": " + e.what());
  }
  if (!ok) throw std::runtime_error("viz: cannot write " + path);
}

CPlot::CPlot(int width, int height) : m_width(width), m_height(height)
{
  if (width < 200 || height < 150)
    throw std::runtime_error("CPlot: size must be at least 200x150, got " + std::to_string(width) +
                             "x" + std::to_string(height));
}

CPlot& CPlot::setXRange(double lo, double hi)
{
  if (!(hi > lo)) throw std::runtime_error("CPlot::setXRange: need lo < hi");
  m_xRange = std::make_pair(lo, hi);
  return *this;
}

CPlot& CPlot::setYRange(double lo, double hi)
{
  if (!(hi > lo)) throw std::runtime_error("CPlot::setYRange: need lo < hi");
  m_yRange = std::make_pair(lo, hi);
  return *this;
}

CPlot& CPlot::addLine(const TPlotSeries& s)
{
  if (s.x.size() != s.y.size())
    throw std::runtime_error("CPlot::addLine: series '" + s.name + "' has " +
                             std::to_string(s.x.size()) + " x but " + std::to_string(s.y.size()) +
                             " y values");
  m_lines.push_back(s);
  return *this;
}

CPlot& CPlot::addStackedAreas(const std::vector<double>& x, const MatX& Y,
    const std::vector<std::string>& names, const std::vector<TColour>& colours)
{
  if (static_cast<Eigen::Index>(x.size()) != Y.rows())
    throw std::runtime_error("CPlot::addStackedAreas: " + std::to_string(x.size()) + " x but " +
                             std::to_string(Y.rows()) + " rows");
  if (static_cast<Eigen::Index>(names.size()) != Y.cols() ||
      static_cast<Eigen::Index>(colours.size()) != Y.cols())
    throw std::runtime_error("CPlot::addStackedAreas: need one name and colour per column");
  m_areas.push_back({x, Y, names, colours});
  return *this;
}

CPlot& CPlot::setBand(const TPlotBand& band)
{
  if (band.x.size() != band.labels.size())
    throw std::runtime_error("CPlot::setBand: " + std::to_string(band.x.size()) + " x but " +
                             std::to_string(band.labels.size()) + " labels");
  if (band.categories.size() != band.colours.size())
    throw std::runtime_error("CPlot::setBand: need one colour per category");
  m_band = band;
  return *this;
}

/** The plot area of a CPlot, its axes, legend and band categories, and the data-to-pixel maps. */
struct CPlot::TLayout
{
  cv::Rect area;
  TAxis ax, ay;
  bool logY = false;
  int tickH = 0, labelH = 0, tickLen = 5, bandH = 0, bandGap = 0;
  std::vector<TLegendItem> legend;
  std::vector<std::string> cats;  ///< band categories: the given ones, then labels not among them
  std::vector<TColour> catColours;
  int swatch = 26, lpad = 8, rowH = 0, legendW = 0, legendH = 0;
  bool legendRight = false;

  double X(double x) const { return area.x + (x - ax.lo) / (ax.hi - ax.lo) * area.width; }
  double Yax(double yAxisUnits) const
  {
    return area.y + area.height - (yAxisUnits - ay.lo) / (ay.hi - ay.lo) * area.height;
  }
  double Y(double y) const { return Yax(logY ? std::log10(y) : y); }
};

cv::Mat CPlot::render() const
{
  if (m_logY && !m_areas.empty())
    throw std::runtime_error("CPlot: stacked areas cannot be drawn on a log y axis");
  double x0, x1, y0, y1;
  dataRanges(x0, x1, y0, y1);
  const TLayout L = layout(x0, x1, y0, y1);
  cv::Mat img(m_height, m_width, CV_8UC3, cv::Scalar(255, 255, 255));
  drawData(img, L);
  drawAxes(img, L);
  drawLegend(img, L);
  return img;
}

void CPlot::dataRanges(double& x0, double& x1, double& y0, double& y1) const
{
  const double inf = std::numeric_limits<double>::infinity();
  x0 = inf, x1 = -inf, y0 = inf, y1 = -inf;
  const auto useY = [&](double y) {
    if (!std::isfinite(y) || (m_logY && y <= 0)) return;
    y0 = std::min(y0, y);
    y1 = std::max(y1, y);
  };
  for (const auto& s : m_lines)
    for (size_t i = 0; i < s.x.size(); ++i)
      if (std::isfinite(s.x[i]) && std::isfinite(s.y[i]))
      {
        x0 = std::min(x0, s.x[i]);
        x1 = std::max(x1, s.x[i]);
        useY(s.y[i]);
      }
  for (const auto& a : m_areas)
  {
    for (double x : a.x)
      if (std::isfinite(x))
      {
        x0 = std::min(x0, x);
        x1 = std::max(x1, x);
      }
    useY(0.0);
    for (Eigen::Index i = 0; i < a.Y.rows(); ++i) useY(a.Y.row(i).sum());
  }
  if (m_xRange) std::tie(x0, x1) = *m_xRange;
  if (!(x1 >= x0)) throw std::runtime_error("CPlot: nothing to plot");
  if (m_yRange) std::tie(y0, y1) = *m_yRange;
  if (!(y1 >= y0))
  {
    y0 = m_logY ? 0.1 : 0.0;
    y1 = m_logY ? 10.0 : 1.0;
  }
  else if (!m_yRange && !m_logY && y1 > y0)
  {
    // 5 % headroom so lines do not run along the frame; keep a zero baseline at zero.
    const double pad = 0.05 * (y1 - y0);
    y0 = (y0 >= 0 && y0 - pad < 0) ? 0.0 : y0 - pad;
    y1 += pad;
  }
  if (m_logY && y0 <= 0) throw std::runtime_error("CPlot: log y axis needs a positive y range");
}

void CPlot::legendItems(TLayout& L) const
{
  std::vector<TLegendItem>& legend = L.legend;
  std::vector<std::string>& cats = L.cats;
  std::vector<TColour>& catColours = L.catColours;
  for (const auto& s : m_lines)
    if (!s.name.empty())
      legend.push_back({TLegendItem::Line, s.name, toBgr(s.colour), s.lineWidth, s.dashed});
  for (const auto& a : m_areas)
    for (size_t k = a.names.size(); k-- > 0;)  // top layer first, as stacked
      legend.push_back({TLegendItem::Box, a.names[k], toBgr(a.colours[k])});
  if (m_band)
  {
    cats = m_band->categories;
    catColours = m_band->colours;
    for (const auto& l : m_band->labels)
      if (!l.empty() && std::find(cats.begin(), cats.end(), l) == cats.end())
      {
        cats.push_back(l);
        catColours.push_back(palette::kNotFound);
      }
    legend.push_back({TLegendItem::Header, m_band->title.empty() ? "band" : m_band->title, kInk});
    for (size_t k = 0; k < cats.size(); ++k)
      legend.push_back({TLegendItem::Box, cats[k], toBgr(catColours[k])});
  }
}

CPlot::TLayout CPlot::layout(double x0, double x1, double y0, double y1) const
{
  TLayout L;
  L.logY = m_logY;
  int base = 0;
  const int tickH = textSize("0", kTickFont, 1, &base).height + base;
  const int labelH = textSize("Ag", kLabelFont, 1).height + base;
  const int titleH = textSize("Ag", kTitleFont, 1).height;
  const int tickLen = 5;

  legendItems(L);
  const std::vector<TLegendItem>& legend = L.legend;
  const int swatch = L.swatch, lpad = L.lpad;
  const int rowH = textSize("Ag", kLegendFont, 1).height + base + 6;
  int legendW = 0;
  for (const auto& it : legend) legendW = std::max(legendW, textSize(it.name, kLegendFont, 1).width);
  legendW += swatch + 3 * lpad;
  const int legendH = int(legend.size()) * rowH + 2 * lpad;
  const bool legendRight = m_legend == ELegend::Right && !legend.empty();

  // Axes (first pass with a provisional plot size to know the tick labels).
  const int provisionalW = m_width - 140 - (legendRight ? legendW + 12 : 0);
  const int provisionalH = m_height - 120;
  TAxis ax = linearAxis(x0, x1, std::max(3, provisionalW / 110), false);
  TAxis ay = m_logY ? logAxis(y0, y1)
                    : linearAxis(y0, y1, std::max(3, provisionalH / 60), !m_yRange);
  if (m_yRange && !m_logY)
  {
    ay.lo = y0;
    ay.hi = y1;
  }
  int yTickW = 0;
  for (const auto& l : ay.labels) yTickW = std::max(yTickW, textSize(l, kTickFont, 1).width);

  const int bandH = m_band ? 16 : 0, bandGap = m_band ? 6 : 0;
  int bandTitleW = 0;
  if (m_band) bandTitleW = textSize(m_band->title, kTickFont, 1).width + 8;
  const int top = m_title.empty() ? 14 : 14 + titleH + 14;
  const int left = std::max(10 + (m_yLabel.empty() ? 0 : labelH + 10) + yTickW + tickLen + 6,
      bandTitleW + 6);
  const int right = 16 + (legendRight ? legendW + 12 : 0);
  const int bottom = bandGap + bandH + tickLen + 6 + tickH + (m_xLabel.empty() ? 6 : labelH + 16);
  const cv::Rect area(left, top, m_width - left - right, m_height - top - bottom);
  if (area.width < 40 || area.height < 40)
    throw std::runtime_error("CPlot: image too small for its labels/legend");
  L.area = area;
  L.ax = ax;
  L.ay = ay;
  L.tickH = tickH;
  L.labelH = labelH;
  L.tickLen = tickLen;
  L.bandH = bandH;
  L.bandGap = bandGap;
  L.rowH = rowH;
  L.legendW = legendW;
  L.legendH = legendH;
  L.legendRight = legendRight;
  return L;
}

void CPlot::drawData(cv::Mat& img, const TLayout& L) const
{
  const cv::Rect& area = L.area;
  const TAxis& ax = L.ax;
  const TAxis& ay = L.ay;
  const auto X = [&](double x) { return L.X(x); };
  const auto Yax = [&](double yAxisUnits) { return L.Yax(yAxisUnits); };
  const auto Y = [&](double y) { return L.Y(y); };
  cv::Mat roi = img(area);
  const auto rx = [&](double x) { return X(x) - area.x; };
  const auto ry = [&](double y) { return Y(y) - area.y; };

  // ---- Grid.
  for (double m : ay.minor)
    cv::line(roi, fp(0, Yax(m) - area.y), fp(area.width, Yax(m) - area.y), kMinorGridInk, 1,
        cv::LINE_8, kShift);
  for (double m : ax.major)
    cv::line(roi, fp(X(m) - area.x, 0), fp(X(m) - area.x, area.height), kGridInk, 1, cv::LINE_8,
        kShift);
  for (double m : ay.major)
    cv::line(roi, fp(0, Yax(m) - area.y), fp(area.width, Yax(m) - area.y), kGridInk, 1,
        cv::LINE_8, kShift);

  // ---- Stacked areas.
  for (const auto& a : m_areas)
  {
    const Eigen::Index T = a.Y.rows(), r = a.Y.cols();
    VecX lower = VecX::Zero(T);
    for (Eigen::Index k = 0; k < r; ++k)
    {
      VecX upper = lower;
      for (Eigen::Index i = 0; i < T; ++i)
        upper[i] += std::isfinite(a.Y(i, k)) ? std::max(0.0, a.Y(i, k)) : 0.0;
      std::vector<cv::Point> poly;
      poly.reserve(2 * T);
      for (Eigen::Index i = 0; i < T; ++i) poly.push_back(fp(rx(a.x[i]), ry(upper[i])));
      for (Eigen::Index i = T; i-- > 0;) poly.push_back(fp(rx(a.x[i]), ry(lower[i])));
      if (T >= 2)
      {
        const std::vector<std::vector<cv::Point>> polys{poly};
        cv::fillPoly(roi, polys, toBgr(a.colours[k]), cv::LINE_8, kShift);
        std::vector<cv::Point> edge(poly.begin(), poly.begin() + T);
        const cv::Scalar c = toBgr(a.colours[k]) * 0.75;
        cv::polylines(roi, edge, false, c, 1, cv::LINE_AA, kShift);
      }
      lower = upper;
    }
  }

  // ---- Lines.
  for (const auto& s : m_lines)
  {
    const cv::Scalar c = toBgr(s.colour);
    double phase = 0;
    bool havePrev = false;
    cv::Point2d prev;
    for (size_t i = 0; i < s.x.size(); ++i)
    {
      const bool ok = std::isfinite(s.x[i]) && std::isfinite(s.y[i]) && (!m_logY || s.y[i] > 0);
      if (!ok)
      {
        havePrev = false;
        continue;
      }
      const cv::Point2d p(rx(s.x[i]), ry(s.y[i]));
      if (havePrev)
      {
        if (s.dashed)
          dashedSegment(roi, prev, p, c, s.lineWidth, phase);
        else
          cv::line(roi, fp(prev.x, prev.y), fp(p.x, p.y), c, s.lineWidth, cv::LINE_AA, kShift);
      }
      if (s.markers)
        cv::circle(roi, fp(p.x, p.y), int(std::lround((s.lineWidth + 1.5) * kOne)), c, cv::FILLED,
            cv::LINE_AA, kShift);
      prev = p;
      havePrev = true;
    }
  }
}

void CPlot::drawAxes(cv::Mat& img, const TLayout& L) const
{
  const cv::Rect& area = L.area;
  const TAxis& ax = L.ax;
  const TAxis& ay = L.ay;
  const auto X = [&](double x) { return L.X(x); };
  const auto Yax = [&](double yAxisUnits) { return L.Yax(yAxisUnits); };
  const int tickLen = L.tickLen, tickH = L.tickH, labelH = L.labelH, bandH = L.bandH, bandGap = L.bandGap;
  const std::vector<std::string>& cats = L.cats;
  const std::vector<TColour>& catColours = L.catColours;

  // ---- Frame, ticks, tick labels.
  cv::rectangle(img, area, kInk, 1, cv::LINE_8);
  const int bandTop = area.y + area.height + bandGap;
  const int tickTop = area.y + area.height + bandGap + bandH;
  for (size_t i = 0; i < ax.major.size(); ++i)
  {
    const int x = static_cast<int>(std::lround(X(ax.major[i])));
    cv::line(img, cv::Point(x, tickTop), cv::Point(x, tickTop + tickLen), kInk, 1, cv::LINE_8);
    const int w = textSize(ax.labels[i], kTickFont, 1).width;
    drawText(img, ax.labels[i], cv::Point(x - w / 2, tickTop + tickLen + 4), kTickFont, kInk);
  }
  for (size_t i = 0; i < ay.major.size(); ++i)
  {
    const int y = static_cast<int>(std::lround(Yax(ay.major[i])));
    cv::line(img, cv::Point(area.x - tickLen, y), cv::Point(area.x, y), kInk, 1, cv::LINE_8);
    const cv::Size sz = textSize(ay.labels[i], kTickFont, 1);
    drawText(img, ay.labels[i], cv::Point(area.x - tickLen - 4 - sz.width, y - sz.height / 2),
        kTickFont, kInk);
  }
  for (double m : ay.minor)
  {
    const int y = static_cast<int>(std::lround(Yax(m)));
    cv::line(img, cv::Point(area.x - 3, y), cv::Point(area.x, y), kInk, 1, cv::LINE_8);
  }

  // ---- Band.
  if (m_band && !m_band->x.empty())
  {
    const auto& b = *m_band;
    cv::Mat strip = img(cv::Rect(area.x, bandTop, area.width, bandH));
    strip.setTo(cv::Scalar(245, 245, 245));
    for (size_t i = 0; i < b.x.size(); ++i)
    {
      if (b.labels[i].empty() || !std::isfinite(b.x[i])) continue;
      const double dl = i > 0 ? b.x[i] - b.x[i - 1] : (b.x.size() > 1 ? b.x[1] - b.x[0] : 1.0);
      const double dr = i + 1 < b.x.size() ? b.x[i + 1] - b.x[i] : dl;
      const auto k = std::find(cats.begin(), cats.end(), b.labels[i]) - cats.begin();
      const double xa = X(b.x[i] - 0.5 * dl) - area.x, xb = X(b.x[i] + 0.5 * dr) - area.x;
      const int ia = static_cast<int>(std::floor(std::max(0.0, xa)));
      const int ib = static_cast<int>(std::ceil(std::min<double>(area.width, xb)));
      if (ib > ia)
        strip(cv::Rect(ia, 0, ib - ia, bandH)).setTo(toBgr(catColours[static_cast<size_t>(k)]));
    }
    cv::rectangle(img, cv::Rect(area.x, bandTop, area.width, bandH), kInk, 1, cv::LINE_8);
    const cv::Size sz = textSize(b.title, kTickFont, 1);
    drawText(img, b.title, cv::Point(area.x - 6 - sz.width, bandTop + (bandH - sz.height) / 2),
        kTickFont, kInk);
  }

  // ---- Axis labels and title.
  if (!m_xLabel.empty())
  {
    const int w = textSize(m_xLabel, kLabelFont, 1).width;
    drawText(img, m_xLabel, cv::Point(area.x + area.width / 2 - w / 2, tickTop + tickLen + 4 + tickH + 8),
        kLabelFont, kInk);
  }
  if (!m_yLabel.empty())
    putRotatedLabel(img, m_yLabel, cv::Point(10 + labelH / 2, area.y + area.height / 2), kLabelFont);
  if (!m_title.empty())
  {
    const int w = textSize(m_title, kTitleFont, 1).width;
    drawText(img, m_title, cv::Point(std::max(4, area.x + area.width / 2 - w / 2), 12), kTitleFont,
        cv::Scalar(0, 0, 0), 1);
  }
}

void CPlot::drawLegend(cv::Mat& img, const TLayout& L) const
{
  const cv::Rect& area = L.area;
  const auto X = [&](double x) { return L.X(x); };
  const auto Y = [&](double y) { return L.Y(y); };
  const std::vector<TLegendItem>& legend = L.legend;
  const int swatch = L.swatch, lpad = L.lpad, rowH = L.rowH, legendW = L.legendW, legendH = L.legendH;
  const bool legendRight = L.legendRight;
  if (!legend.empty() && m_legend != ELegend::None)
  {
    cv::Rect box(area.x + area.width - legendW - 8, area.y + 8, legendW, legendH);
    if (legendRight) box = cv::Rect(area.x + area.width + 12, area.y, legendW, legendH);
    if (m_legend == ELegend::InsideBest)
    {
      // Corners in order of preference; keep the one with the fewest data points under it.
      const cv::Rect cand[4] = {box,
          cv::Rect(area.x + 8, area.y + 8, legendW, legendH),
          cv::Rect(area.x + area.width - legendW - 8, area.y + area.height - legendH - 8, legendW,
              legendH),
          cv::Rect(area.x + 8, area.y + area.height - legendH - 8, legendW, legendH)};
      long best = -1;
      for (const auto& c : cand)
      {
        long n = 0;
        for (const auto& sr : m_lines)
          for (size_t i = 0; i < sr.x.size(); ++i)
          {
            if (!std::isfinite(sr.x[i]) || !std::isfinite(sr.y[i]) || (m_logY && sr.y[i] <= 0))
              continue;
            const cv::Point p(int(X(sr.x[i])), int(Y(sr.y[i])));
            n += c.contains(p) ? 1 : 0;
          }
        if (best < 0 || n < best)
        {
          best = n;
          box = c;
        }
      }
    }
    blendRect(img, box, cv::Scalar(255, 255, 255), 0.85);
    cv::rectangle(img, box, cv::Scalar(190, 190, 190), 1, cv::LINE_8);
    for (size_t i = 0; i < legend.size(); ++i)
    {
      const auto& it = legend[i];
      const int y = box.y + lpad + int(i) * rowH;
      const int cy = y + rowH / 2;
      const int sx = box.x + lpad;
      if (it.kind == TLegendItem::Line)
      {
        if (it.dashed)
        {
          double ph = 0;
          dashedSegment(img, cv::Point2d(sx, cy), cv::Point2d(sx + swatch, cy), it.colour, it.width, ph);
        }
        else
          cv::line(img, cv::Point(sx, cy), cv::Point(sx + swatch, cy), it.colour, it.width, cv::LINE_AA);
      }
      else if (it.kind == TLegendItem::Box)
      {
        cv::rectangle(img, cv::Rect(sx + 3, cy - rowH / 2 + 3, swatch - 6, rowH - 6), it.colour, cv::FILLED);
        cv::rectangle(img, cv::Rect(sx + 3, cy - rowH / 2 + 3, swatch - 6, rowH - 6), kInk * 1.5, 1);
      }
      const int tx = it.kind == TLegendItem::Header ? sx : sx + swatch + lpad;
      const cv::Size sz = textSize(it.name, kLegendFont, 1);
      drawText(img, it.name, cv::Point(tx, cy - sz.height / 2 - 1), kLegendFont, kInk);
    }
  }
}

void CPlot::save(const std::string& png) const { writePng(render(), png); }
}  // namespace immslam::viz
