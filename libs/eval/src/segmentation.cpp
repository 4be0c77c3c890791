/* imm-monoslam — motion segmentation accuracy from model probabilities and motion labels. */
#include <immslam/eval/segmentation.h>

#include "table_reader.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <ostream>
#include <stdexcept>

namespace immslam::eval
{
namespace
{
bool isKnownLabel(const std::string& s) { return s == "stationary" || s == "rotation" || s == "general"; }

std::ptrdiff_t indexOf(const std::vector<std::string>& v, const std::string& s)
{
  const auto it = std::find(v.begin(), v.end(), s);
  return it == v.end() ? -1 : it - v.begin();
}
}  // namespace

std::string modelFamily(const std::string& modelName) { return modelName.substr(0, modelName.find('_')); }

TModelProbabilities readModelProbabilitiesCsv(const std::string& path)
{
  detail::CTableReader r(path, detail::CTableReader::ESeparator::Comma, "model probabilities file");
  TModelProbabilities out;
  if (!r.next()) throw std::runtime_error(path + ": empty file (expected a header 'timestamp,<model name>...')");
  if (r.fields().size() < 2 || r.fields()[0] != "timestamp")
    r.fail("expected a header 'timestamp,<model name>...'");
  out.modelNames.assign(r.fields().begin() + 1, r.fields().end());
  for (std::size_t j = 0; j < out.modelNames.size(); ++j)
    if (out.modelNames[j].empty()) r.fail("empty model name in column " + std::to_string(j + 2));
  const std::size_t nCols = out.modelNames.size() + 1;
  std::vector<std::vector<double>> rows;
  while (r.next())
  {
    r.requireFields(nCols, "timestamp and " + std::to_string(nCols - 1) + " probabilities");
    std::vector<double> row(nCols);
    row[0] = r.number(0, "timestamp");
    for (std::size_t j = 1; j < nCols; ++j) row[j] = r.number(j, out.modelNames[j - 1]);
    rows.push_back(std::move(row));
  }
  out.times.resize(rows.size());
  out.probs.resize(static_cast<Eigen::Index>(rows.size()), static_cast<Eigen::Index>(nCols - 1));
  for (std::size_t k = 0; k < rows.size(); ++k)
  {
    out.times[k] = rows[k][0];
    for (std::size_t j = 1; j < nCols; ++j)
      out.probs(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(j - 1)) = rows[k][j];
  }
  return out;
}

TFamilyProbabilities familyProbabilities(const std::vector<std::string>& modelNames, const MatX& probs)
{
  if (static_cast<std::size_t>(probs.cols()) != modelNames.size())
    throw std::invalid_argument("familyProbabilities: " + std::to_string(probs.cols()) + " probability columns for " +
                                std::to_string(modelNames.size()) + " model names");
  TFamilyProbabilities out;
  std::vector<std::size_t> famOf(modelNames.size());
  for (std::size_t j = 0; j < modelNames.size(); ++j)
  {
    const std::string fam = modelFamily(modelNames[j]);
    std::ptrdiff_t i = indexOf(out.families, fam);
    if (i < 0) i = static_cast<std::ptrdiff_t>(out.families.size()), out.families.push_back(fam);
    famOf[j] = static_cast<std::size_t>(i);
  }
  out.probs = MatX::Zero(probs.rows(), static_cast<Eigen::Index>(out.families.size()));
  // Column order within each family, so that the sums equal a left-to-right sum over the row.
  for (Eigen::Index k = 0; k < probs.rows(); ++k)
    for (std::size_t j = 0; j < modelNames.size(); ++j)
      out.probs(k, static_cast<Eigen::Index>(famOf[j])) += probs(k, static_cast<Eigen::Index>(j));
  return out;
}

TMotionLabels readMotionLabels(const std::string& path)
{
  detail::CTableReader r(path, detail::CTableReader::ESeparator::Whitespace, "motion labels file");
  TMotionLabels out;
  while (r.next())
  {
    r.requireFields(2, "timestamp label");
    const double t = r.number(0, "timestamp");
    const std::string& label = r.fields()[1];
    if (!isKnownLabel(label)) r.fail("unknown motion label '" + label + "' (expected stationary, rotation or general)");
    out.times.push_back(t);
    out.labels.push_back(label);
  }
  return out;
}

std::vector<std::string> labelsAtTimes(const TMotionLabels& labels, const std::vector<double>& times, double maxDt)
{
  if (labels.times.size() != labels.labels.size())
    throw std::invalid_argument("labelsAtTimes: " + std::to_string(labels.times.size()) + " times for " +
                                std::to_string(labels.labels.size()) + " labels");
  std::vector<std::size_t> order(labels.times.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return labels.times[a] < labels.times[b]; });
  std::vector<double> sorted(order.size());
  for (std::size_t i = 0; i < order.size(); ++i) sorted[i] = labels.times[order[i]];
  std::vector<std::string> out(times.size());
  for (std::size_t k = 0; k < times.size(); ++k)
    if (const auto i = detail::nearestTime(sorted, times[k], maxDt); i >= 0)
      out[k] = labels.labels[order[static_cast<std::size_t>(i)]];
  return out;
}

std::size_t TSegmentationResult::count(const std::string& truth, const std::string& decided) const
{
  const auto i = indexOf(classes, truth), j = indexOf(classes, decided);
  return i < 0 || j < 0 ? 0 : confusion[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)];
}

std::size_t TSegmentationResult::labelled(const std::string& truth) const
{
  const auto i = indexOf(classes, truth);
  if (i < 0) return 0;
  const auto& row = confusion[static_cast<std::size_t>(i)];
  return std::accumulate(row.begin(), row.end(), std::size_t{0});
}

double TSegmentationResult::recall(const std::string& truth) const
{
  const std::size_t n = labelled(truth);
  return n ? static_cast<double>(count(truth, truth)) / static_cast<double>(n)
           : std::numeric_limits<double>::quiet_NaN();
}

std::string TSegmentationResult::summary() const
{
  char buf[256];
  std::string s;
  std::snprintf(buf, sizeof buf,
                "motion segmentation: accuracy %.2f %% (%zu/%zu frames counted; %zu within %.3g s of one of %zu "
                "label changes excluded; %zu unlabelled)\n",
                100 * accuracy, nCorrect, nCounted, nExcluded, excludeAroundTransitionsS, transitions.size(),
                nUnlabelled);
  s += buf;
  std::size_t w = 12;
  for (const auto& c : classes) w = std::max(w, c.size() + 2);
  const auto pad = [](const std::string& x, std::size_t n) { return x + std::string(n > x.size() ? n - x.size() : 0, ' '); };
  s += "  " + pad("label \\ decided", w + 4);
  for (const auto& c : classes) s += pad(c, w);
  s += "recall\n";
  for (std::size_t i = 0; i < classes.size(); ++i)
  {
    s += "  " + pad(classes[i], w + 4);
    for (std::size_t j = 0; j < classes.size(); ++j) s += pad(std::to_string(confusion[i][j]), w);
    const double r = recall(classes[i]);
    if (std::isnan(r))
      s += "n/a\n";
    else
    {
      std::snprintf(buf, sizeof buf, "%.2f %%\n", 100 * r);
      s += buf;
    }
  }
  return s;
}

std::ostream& operator<<(std::ostream& os, const TSegmentationResult& r) { return os << r.summary(); }

TSegmentationResult segmentationAccuracy(const std::vector<double>& times, const std::vector<std::string>& modelNames,
                                         const MatX& probs, const std::vector<std::string>& labels,
                                         double excludeAroundTransitionsS)
{
  if (static_cast<std::size_t>(probs.rows()) != times.size() || labels.size() != times.size())
    throw std::invalid_argument("segmentationAccuracy: " + std::to_string(times.size()) + " times, " +
                                std::to_string(probs.rows()) + " probability rows and " +
                                std::to_string(labels.size()) + " labels");
  if (!(excludeAroundTransitionsS >= 0))
    throw std::invalid_argument("segmentationAccuracy: the exclusion window must be >= 0 s");
  const TFamilyProbabilities fam = familyProbabilities(modelNames, probs);

  TSegmentationResult r;
  r.nFrames = times.size();
  r.excludeAroundTransitionsS = excludeAroundTransitionsS;
  r.classes = fam.families;
  for (const auto& l : labels)
    if (!l.empty() && indexOf(r.classes, l) < 0) r.classes.push_back(l);
  r.confusion.assign(r.classes.size(), std::vector<std::size_t>(r.classes.size(), 0));

  const std::string* previous = nullptr;
  for (std::size_t k = 0; k < times.size(); ++k)
  {
    if (labels[k].empty()) continue;
    if (previous && *previous != labels[k]) r.transitions.push_back(times[k]);
    previous = &labels[k];
  }

  for (std::size_t k = 0; k < times.size(); ++k)
  {
    if (labels[k].empty())
    {
      ++r.nUnlabelled;
      continue;
    }
    bool near = false;
    for (const double t : r.transitions) near = near || std::abs(times[k] - t) < excludeAroundTransitionsS;
    if (near)
    {
      ++r.nExcluded;
      continue;
    }
    std::size_t best = 0;
    double bestP = -std::numeric_limits<double>::infinity();
    for (Eigen::Index f = 0; f < fam.probs.cols(); ++f)
      if (const double p = fam.probs(static_cast<Eigen::Index>(k), f); p > bestP) bestP = p, best = static_cast<std::size_t>(f);
    const auto truth = static_cast<std::size_t>(indexOf(r.classes, labels[k]));
    ++r.confusion[truth][best];
    ++r.nCounted;
    if (truth == best) ++r.nCorrect;
  }
  r.accuracy = r.nCounted ? static_cast<double>(r.nCorrect) / static_cast<double>(r.nCounted)
                          : std::numeric_limits<double>::quiet_NaN();
  return r;
}

TSegmentationResult segmentationAccuracy(const TModelProbabilities& p, const TMotionLabels& labels,
                                         double excludeAroundTransitionsS, double maxDt)
{
  const std::vector<std::string> l = labelsAtTimes(labels, p.times, maxDt);
  if (std::all_of(l.begin(), l.end(), [](const std::string& s) { return s.empty(); }))
    throw std::runtime_error("no model probability row has a motion label within " + std::to_string(maxDt) +
                             " s of its timestamp");
  return segmentationAccuracy(p.times, p.modelNames, p.probs, l, excludeAroundTransitionsS);
}
}  // namespace immslam::eval
