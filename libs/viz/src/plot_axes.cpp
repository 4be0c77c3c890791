/* imm-monoslam — the axes of CPlot (see plot_axes.h). */
#include "plot_axes.h"

#include "cv_text.h"

#include <algorithm>
#include <cmath>

namespace immslam::viz::detail
{
namespace
{
/** A 1-2-2.5-5 step for about targetTicks ticks over `range`. */
double niceStep(double range, int targetTicks)
{
  const double raw = range / std::max(1, targetTicks);
  const double e = std::floor(std::log10(raw));
  const double f = raw / std::pow(10.0, e);
  const double nf = f <= 1.0 ? 1 : (f <= 2.0 ? 2 : (f <= 2.5 ? 2.5 : (f <= 5.0 ? 5 : 10)));
  return nf * std::pow(10.0, e);
}
}  // namespace

/** Linear axis; `loose` widens lo/hi to multiples of the step. */
TAxis linearAxis(double lo, double hi, int targetTicks, bool loose)
{
  if (!(hi > lo))
  {
    const double c = std::isfinite(lo) ? lo : 0.0, h = std::max(1e-9, std::abs(c) * 0.05 + 0.5);
    lo = c - h;
    hi = c + h;
  }
  TAxis a;
  const double step = niceStep(hi - lo, targetTicks);
  if (loose)
  {
    lo = std::floor(lo / step + 1e-9) * step;
    hi = std::ceil(hi / step - 1e-9) * step;
  }
  a.lo = lo;
  a.hi = hi;
  const long k0 = static_cast<long>(std::ceil(lo / step - 1e-9));
  const long k1 = static_cast<long>(std::floor(hi / step + 1e-9));
  // Decimals needed by the step (e.g. 0.25 -> 2).
  int dec = 0;
  while (dec < 10 && std::abs(step * std::pow(10.0, dec) - std::round(step * std::pow(10.0, dec))) >
                         1e-6 * step * std::pow(10.0, dec))
    ++dec;
  for (long k = k0; k <= k1; ++k)
  {
    const double v = k * step;
    a.major.push_back(v);
    const double r = std::abs(v) < 1e-12 * step ? 0.0 : v;
    const double mag = std::max(std::abs(lo), std::abs(hi));
    if (mag >= 1e5 || (mag < 1e-3 && mag > 0))
      a.labels.push_back(formatNumber(r, 3));
    else
    {
      char buf[64];
      std::snprintf(buf, sizeof buf, "%.*f", dec, r);
      a.labels.push_back(buf);
    }
  }
  return a;
}

/** Log-10 axis over [lo, hi] > 0 (decades rounded outwards). */
TAxis logAxis(double lo, double hi)
{
  TAxis a;
  double l = std::floor(std::log10(lo) + 1e-9), h = std::ceil(std::log10(hi) - 1e-9);
  if (h <= l) h = l + 1;
  a.lo = l;
  a.hi = h;
  const int decades = static_cast<int>(h - l);
  const int every = decades > 8 ? (decades + 7) / 8 : 1;
  for (int k = static_cast<int>(l); k <= static_cast<int>(h); ++k)
  {
    if ((k - static_cast<int>(l)) % every == 0)
    {
      a.major.push_back(k);
      a.labels.push_back(formatNumber(std::pow(10.0, k), 3));
    }
    if (decades <= 6 && k < h)
      for (int m = 2; m <= 9; ++m) a.minor.push_back(k + std::log10(m));
  }
  return a;
}
}  // namespace immslam::viz::detail
