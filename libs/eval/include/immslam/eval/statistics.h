/* imm-monoslam — small descriptive statistics over std::vector<double>. */
#pragma once

#include <cstddef>
#include <vector>

namespace immslam::eval
{
/** Arithmetic mean. \throws std::invalid_argument on empty input (as all functions here). */
double mean(const std::vector<double>& v);

/** Root mean square \f$ \sqrt{\frac1n \sum v_i^2} \f$. */
double rms(const std::vector<double>& v);

/** Median (mean of the two middle values for even sizes). */
double median(const std::vector<double>& v);

/** Percentile p in [0, 100] with linear interpolation between order statistics: the value at
 * rank \f$ (p/100)(n-1) \f$ of the sorted data (numpy's default "linear" method).
 * \throws std::invalid_argument if p is outside [0, 100]. */
double percentile(const std::vector<double>& v, double p);

/** Largest value. */
double maxValue(const std::vector<double>& v);

/** Smallest value. */
double minValue(const std::vector<double>& v);

/** Population standard deviation \f$ \sqrt{\frac1n \sum (v_i - \bar v)^2} \f$. */
double stddev(const std::vector<double>& v);

/** All of the above at once. */
struct TSummaryStats
{
  size_t n = 0;
  double mean = 0, rms = 0, median = 0, min = 0, max = 0, stddev = 0;
};

/** Summary statistics of a non-empty vector. */
TSummaryStats summarize(const std::vector<double>& v);
}  // namespace immslam::eval
