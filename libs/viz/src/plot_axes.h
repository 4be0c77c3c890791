/* imm-monoslam — private to libs/viz: the axes of CPlot (tick positions and labels). */
#pragma once

#include <string>
#include <vector>

namespace immslam::viz::detail
{
/** An axis of a plot. */
struct TAxis
{
  double lo = 0, hi = 1;        // in axis units (log10 for a log axis)
  std::vector<double> major;    // tick positions in axis units
  std::vector<double> minor;    // minor ticks (log axis)
  std::vector<std::string> labels;
};

/** Linear axis over [lo, hi] with about targetTicks ticks at a 1-2-2.5-5 step; `loose` widens lo/hi
 * to multiples of the step. */
TAxis linearAxis(double lo, double hi, int targetTicks, bool loose);

/** Log-10 axis over [lo, hi] > 0 (decades rounded outwards). */
TAxis logAxis(double lo, double hi);
}  // namespace immslam::viz::detail
