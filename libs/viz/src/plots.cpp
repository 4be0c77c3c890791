/* imm-monoslam — standard figures built on CPlot. */
#include <immslam/viz/plots.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace immslam::viz
{
namespace
{
bool startsWith(const std::string& s, const char* p) { return s.rfind(p, 0) == 0; }

TColour lerp(const TColour& a, const TColour& b, double t)
{
  const auto m = [t](int x, int y) { return static_cast<std::uint8_t>(std::lround(x + (y - x) * t)); };
  return TColour(m(a.r, b.r), m(a.g, b.g), m(a.b, b.b));
}

// Distinct colours for names outside the known families (colour-blind friendly order).
constexpr TColour kOthers[] = {{0, 114, 178}, {230, 159, 0}, {0, 158, 115}, {204, 121, 167},
    {86, 180, 233}, {213, 94, 0}, {240, 228, 66}, {0, 0, 0}};
}  // namespace

TColour familyColour(const std::string& label)
{
  if (startsWith(label, "stationary")) return TColour(110, 110, 110);
  if (startsWith(label, "rotation")) return TColour(60, 120, 210);
  if (startsWith(label, "general")) return TColour(235, 120, 30);
  return TColour(190, 190, 190);
}

std::vector<TColour> modelColours(const std::vector<std::string>& names)
{
  const char* fams[3] = {"stationary", "rotation", "general"};
  const TColour light[3] = {{150, 150, 150}, {150, 195, 240}, {253, 195, 110}};
  const TColour dark[3] = {{70, 70, 70}, {20, 60, 150}, {185, 30, 20}};
  int count[3] = {0, 0, 0};
  for (const auto& n : names)
    for (int f = 0; f < 3; ++f)
      if (startsWith(n, fams[f])) ++count[f];
  int seen[3] = {0, 0, 0}, other = 0;
  std::vector<TColour> out;
  for (const auto& n : names)
  {
    int fam = -1;
    for (int f = 0; f < 3; ++f)
      if (startsWith(n, fams[f])) fam = f;
    if (fam < 0)
    {
      out.push_back(kOthers[other++ % 8]);
      continue;
    }
    const double t = count[fam] > 1 ? double(seen[fam]) / (count[fam] - 1) : 0.5;
    out.push_back(lerp(light[fam], dark[fam], t));
    ++seen[fam];
  }
  return out;
}

cv::Mat modelProbabilitiesImage(const std::vector<double>& times,
    const std::vector<std::string>& names, const MatX& probs, const TModelProbabilityPlotOptions& o)
{
  if (probs.rows() != static_cast<Eigen::Index>(times.size()))
    throw std::runtime_error("plotModelProbabilities: " + std::to_string(times.size()) +
                             " times but " + std::to_string(probs.rows()) + " rows");
  if (probs.cols() != static_cast<Eigen::Index>(names.size()))
    throw std::runtime_error("plotModelProbabilities: " + std::to_string(names.size()) +
                             " names but " + std::to_string(probs.cols()) + " columns");
  if (!o.truthLabels.empty() && o.truthLabels.size() != times.size())
    throw std::runtime_error("plotModelProbabilities: " + std::to_string(o.truthLabels.size()) +
                             " truth labels for " + std::to_string(times.size()) + " frames");
  if (times.empty()) throw std::runtime_error("plotModelProbabilities: no frames");
  const std::vector<TColour> colours = o.colours.empty() ? modelColours(names) : o.colours;
  if (colours.size() != names.size())
    throw std::runtime_error("plotModelProbabilities: need one colour per model");

  CPlot p(o.width, o.height);
  p.setTitle(o.title).setXLabel(o.xLabel).setYLabel("probability").setLegend(ELegend::Right);
  if (o.style == EProbabilityStyle::StackedAreas)
  {
    p.addStackedAreas(times, probs, names, colours).setYRange(0.0, 1.0);
  }
  else
  {
    p.setLogY(o.logY);
    if (o.logY)
      p.setYRange(std::max(1e-300, o.minProbability), 1.0);
    else
      p.setYRange(0.0, 1.0);
    for (Eigen::Index k = 0; k < probs.cols(); ++k)
    {
      TPlotSeries s;
      s.name = names[static_cast<size_t>(k)];
      s.colour = colours[static_cast<size_t>(k)];
      s.lineWidth = 2;
      s.x = times;
      s.y.resize(times.size());
      for (Eigen::Index i = 0; i < probs.rows(); ++i)
        s.y[static_cast<size_t>(i)] =
            o.logY ? std::max(probs(i, k), o.minProbability) : probs(i, k);
      p.addLine(s);
    }
  }
  if (!times.empty()) p.setXRange(times.front(), std::max(times.back(), times.front() + 1e-9));
  if (!o.truthLabels.empty())
  {
    TPlotBand b;
    b.title = o.truthTitle;
    b.x = times;
    b.labels = o.truthLabels;
    for (const auto& l : o.truthLabels)
      if (!l.empty() && std::find(b.categories.begin(), b.categories.end(), l) == b.categories.end())
      {
        b.categories.push_back(l);
        b.colours.push_back(familyColour(l));
      }
    p.setBand(b);
  }
  return p.render();
}

void plotModelProbabilities(const std::vector<double>& times, const std::vector<std::string>& names,
    const MatX& probs, const std::string& png, const TModelProbabilityPlotOptions& o)
{
  writePng(modelProbabilitiesImage(times, names, probs, o), png);
}

cv::Mat seriesImage(const std::vector<TPlotSeries>& series, const TSeriesPlotOptions& o)
{
  if (series.empty()) throw std::runtime_error("plotSeries: no series");
  CPlot p(o.width, o.height);
  p.setTitle(o.title).setXLabel(o.xLabel).setYLabel(o.yLabel).setLogY(o.logY).setLegend(o.legend);
  if (o.yRange) p.setYRange(o.yRange->first, o.yRange->second);
  for (const auto& s : series) p.addLine(s);
  return p.render();
}

void plotSeries(const std::vector<TPlotSeries>& series, const std::string& png,
    const TSeriesPlotOptions& o)
{
  writePng(seriesImage(series, o), png);
}
}  // namespace immslam::viz
