/* imm-monoslam — descriptive statistics. */
#include <immslam/eval/statistics.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace immslam::eval
{
namespace
{
void requireNonEmpty(const std::vector<double>& v, const char* fn)
{
  if (v.empty()) throw std::invalid_argument(std::string(fn) + ": empty input");
}

/** Value at fractional rank r in [0, n-1] of the data (sorted copy, linear interpolation). */
double atRank(std::vector<double> v, double r)
{
  const size_t lo = static_cast<size_t>(std::floor(r));
  const size_t hi = std::min(lo + 1, v.size() - 1);
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(lo), v.end());
  const double a = v[lo];
  if (hi == lo || r == static_cast<double>(lo)) return a;
  // The next order statistic is the smallest element after position lo.
  const double b = *std::min_element(v.begin() + static_cast<std::ptrdiff_t>(lo) + 1, v.end());
  return a + (r - static_cast<double>(lo)) * (b - a);
}
}  // namespace

double mean(const std::vector<double>& v)
{
  requireNonEmpty(v, "mean");
  double s = 0;
  for (double x : v) s += x;
  return s / static_cast<double>(v.size());
}

double rms(const std::vector<double>& v)
{
  requireNonEmpty(v, "rms");
  double s = 0;
  for (double x : v) s += x * x;
  return std::sqrt(s / static_cast<double>(v.size()));
}

double median(const std::vector<double>& v)
{
  requireNonEmpty(v, "median");
  return atRank(v, 0.5 * static_cast<double>(v.size() - 1));
}

double percentile(const std::vector<double>& v, double p)
{
  requireNonEmpty(v, "percentile");
  if (!(p >= 0 && p <= 100)) throw std::invalid_argument("percentile: p must be in [0, 100]");
  return atRank(v, p / 100.0 * static_cast<double>(v.size() - 1));
}

double maxValue(const std::vector<double>& v)
{
  requireNonEmpty(v, "maxValue");
  return *std::max_element(v.begin(), v.end());
}

double minValue(const std::vector<double>& v)
{
  requireNonEmpty(v, "minValue");
  return *std::min_element(v.begin(), v.end());
}

double stddev(const std::vector<double>& v)
{
  const double m = mean(v);
  double s = 0;
  for (double x : v) s += (x - m) * (x - m);
  return std::sqrt(s / static_cast<double>(v.size()));
}

TSummaryStats summarize(const std::vector<double>& v)
{
  requireNonEmpty(v, "summarize");
  TSummaryStats s;
  s.n = v.size();
  s.mean = mean(v);
  s.rms = rms(v);
  s.median = median(v);
  s.min = minValue(v);
  s.max = maxValue(v);
  s.stddev = stddev(v);
  return s;
}
}  // namespace immslam::eval
