/* imm-monoslam — the project's standard figures: IMM model probabilities (IMM paper Fig. 4),
 * search-ellipse areas (IMM vs single model), errors over time. */
#pragma once

#include <immslam/math/types.h>
#include <immslam/viz/CPlot.h>

#include <opencv2/core.hpp>

#include <optional>
#include <string>
#include <vector>

namespace immslam::viz
{
/** How model probabilities are drawn. */
enum class EProbabilityStyle
{
  StackedAreas,  ///< filled areas stacked to 1 (which model dominates when)
  Lines          ///< one line per model (use logY to see the small ones, as the paper's Fig. 4)
};

/** Options of plotModelProbabilities(). */
struct TModelProbabilityPlotOptions
{
  int width = 1000;   ///< image width (pixels)
  int height = 460;   ///< image height (pixels)
  std::string title = "Posterior model probabilities";  ///< figure title
  std::string xLabel = "time [s]";  ///< x axis label
  EProbabilityStyle style = EProbabilityStyle::StackedAreas;  ///< areas or lines
  bool logY = false;        ///< log y axis (Lines only), from minProbability to 1
  double minProbability = 1e-4;  ///< lower end of the log axis
  /** One label per frame (e.g. "stationary", "rotation", "general"), drawn as a coloured band
   * under the axes; empty: no band. Labels naming a model family get that family's colour. */
  std::vector<std::string> truthLabels;
  std::string truthTitle = "truth";  ///< band caption
  std::vector<TColour> colours;  ///< one per model (empty: modelColours(names))
};

/** Colours for model names by family (name prefix): "stationary..." grey, "rotation..." blues,
 * "general..." oranges to reds (lighter for the first of a family, darker for the last); other
 * names get distinct colours in order. */
std::vector<TColour> modelColours(const std::vector<std::string>& names);

/** The colour of a family label ("stationary", "rotation", "general"; others: grey). */
TColour familyColour(const std::string& label);

/** Draws the posterior model probabilities mu_k over time (IMM paper Fig. 4).
 * \param times T sample times; \param names r model names; \param probs T x r probabilities.
 * \throws std::runtime_error on size mismatches or if the PNG cannot be written (names it). */
void plotModelProbabilities(const std::vector<double>& times, const std::vector<std::string>& names,
    const MatX& probs, const std::string& png,
    const TModelProbabilityPlotOptions& options = TModelProbabilityPlotOptions());

/** The same figure as an image (BGR). */
cv::Mat modelProbabilitiesImage(const std::vector<double>& times,
    const std::vector<std::string>& names, const MatX& probs,
    const TModelProbabilityPlotOptions& options = TModelProbabilityPlotOptions());

/** Options of plotSeries(). */
struct TSeriesPlotOptions
{
  int width = 900;     ///< image width (pixels)
  int height = 420;    ///< image height (pixels)
  std::string title;   ///< figure title
  std::string xLabel = "time [s]";  ///< x axis label
  std::string yLabel;  ///< y axis label
  bool logY = false;   ///< log y axis (e.g. search-ellipse areas)
  std::optional<std::pair<double, double>> yRange;  ///< fixed y range
  ELegend legend = ELegend::InsideBest;  ///< legend placement
};

/** Plots several series (e.g. mean search-ellipse area of IMM vs single model, or ATE over time).
 * Series without a colour keep theirs (TPlotSeries::colour).
 * \throws std::runtime_error on bad series or if the PNG cannot be written (names it). */
void plotSeries(const std::vector<TPlotSeries>& series, const std::string& png,
    const TSeriesPlotOptions& options = TSeriesPlotOptions());

/** The same figure as an image (BGR). */
cv::Mat seriesImage(
    const std::vector<TPlotSeries>& series, const TSeriesPlotOptions& options = TSeriesPlotOptions());
}  // namespace immslam::viz
