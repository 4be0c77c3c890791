/* imm-monoslam — a small deterministic plotting helper (OpenCV drawing, PNG output). */
#pragma once

#include <immslam/math/types.h>
#include <immslam/viz/colours.h>

#include <opencv2/core.hpp>

#include <optional>
#include <string>
#include <vector>

namespace immslam::viz
{
/** One line series. Non-finite points (and, with a log y axis, non-positive ones) break the line. */
struct TPlotSeries
{
  std::string name;        ///< legend label (empty: not in the legend)
  std::vector<double> x;   ///< abscissae (same size as y)
  std::vector<double> y;   ///< ordinates
  TColour colour = palette::kTrajectory;  ///< line colour
  int lineWidth = 2;       ///< pixels
  bool markers = false;    ///< small dots at the points
  bool dashed = false;     ///< dashed line
};

/** A categorical strip under the axes: interval [x_i - dx/2, x_i + dx/2] gets the colour of
 * labels[i] (e.g. the true motion class of each frame). */
struct TPlotBand
{
  std::string title;                 ///< drawn left of the strip
  std::vector<double> x;             ///< sample abscissae (increasing)
  std::vector<std::string> labels;   ///< one label per sample (empty label: no colour)
  std::vector<std::string> categories;  ///< legend order (labels not listed are appended)
  std::vector<TColour> colours;      ///< colour of each category (same order)
};

/** Where the legend goes. */
enum class ELegend
{
  Right,          ///< outside the axes, on the right
  InsideTopRight, ///< inside the axes, top-right corner
  InsideBest,     ///< inside the axes, in the corner covering the fewest line points
  None            ///< no legend
};

/** A 2-D plot: axes with ticks and labels, title, legend, line series, stacked filled areas, an
 * optional categorical band, linear or log-10 y axis. Same input, same pixels (no clock, no
 * randomness, no locale dependence).
 *
 * \code
 *   CPlot p(900, 450);
 *   p.setTitle("ATE").setXLabel("time [s]").setYLabel("error");
 *   p.addLine({"IMM", t, e1, palette::kTrajectory});
 *   p.save("ate.png");
 * \endcode */
class CPlot
{
 public:
  /** \throws std::runtime_error if the size is below 200 x 150. */
  CPlot(int width = 900, int height = 500);

  CPlot& setTitle(const std::string& s) { m_title = s; return *this; }   ///< title above the axes
  CPlot& setXLabel(const std::string& s) { m_xLabel = s; return *this; } ///< x axis label
  CPlot& setYLabel(const std::string& s) { m_yLabel = s; return *this; } ///< y axis label (rotated)
  CPlot& setLogY(bool v) { m_logY = v; return *this; }  ///< log-10 y axis
  CPlot& setXRange(double lo, double hi);  ///< fixed x range (else: the data's)
  CPlot& setYRange(double lo, double hi);  ///< fixed y range (else: the data's, padded)
  CPlot& setLegend(ELegend where) { m_legend = where; return *this; }  ///< legend placement

  /** Adds a line series. \throws std::runtime_error if x and y sizes differ. */
  CPlot& addLine(const TPlotSeries& s);

  /** Adds filled stacked areas: layer k spans [sum_{j<k} Y(:,j), sum_{j<=k} Y(:,j)].
   * \param Y one row per x, one column per layer; \param names/colours one per column.
   * \throws std::runtime_error on size mismatches. Not allowed with a log y axis (render throws). */
  CPlot& addStackedAreas(const std::vector<double>& x, const MatX& Y,
      const std::vector<std::string>& names, const std::vector<TColour>& colours);

  /** Sets the categorical band (one per plot). \throws std::runtime_error on size mismatches. */
  CPlot& setBand(const TPlotBand& band);

  /** Draws the plot. \throws std::runtime_error if there is nothing to plot or log y with areas. */
  cv::Mat render() const;

  /** render() and writes a PNG. \throws std::runtime_error naming the path on failure. */
  void save(const std::string& png) const;

 private:
  struct TLayout;  ///< plot area, axes, legend (CPlot.cpp)
  /** The x and y ranges of the data (finite points; y > 0 on a log axis). */
  void dataRanges(double& x0, double& x1, double& y0, double& y1) const;
  /** The legend's items and the band's categories into L. */
  void legendItems(TLayout& L) const;
  /** The layout for data in [x0, x1] x [y0, y1]: axes, plot area, legend. */
  TLayout layout(double x0, double x1, double y0, double y1) const;
  /** Grid, stacked areas and lines inside the plot area. */
  void drawData(cv::Mat& img, const TLayout& L) const;
  /** Frame, ticks and their labels, the band, axis labels and title. */
  void drawAxes(cv::Mat& img, const TLayout& L) const;
  /** The legend box. */
  void drawLegend(cv::Mat& img, const TLayout& L) const;

  struct TArea
  {
    std::vector<double> x;
    MatX Y;
    std::vector<std::string> names;
    std::vector<TColour> colours;
  };
  int m_width, m_height;
  std::string m_title, m_xLabel, m_yLabel;
  bool m_logY = false;
  std::optional<std::pair<double, double>> m_xRange, m_yRange;
  ELegend m_legend = ELegend::Right;
  std::vector<TPlotSeries> m_lines;
  std::vector<TArea> m_areas;
  std::optional<TPlotBand> m_band;
};

/** Writes an image as PNG. \throws std::runtime_error naming the path on failure. */
void writePng(const cv::Mat& img, const std::string& path);
}  // namespace immslam::viz
