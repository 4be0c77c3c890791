/* imm-monoslam — chi-square distribution from the regularized incomplete gamma function. */
#include <immslam/math/chi2.h>

#include <cmath>
#include <limits>
#include <stdexcept>

namespace immslam::math
{
double regularizedGammaP(double a, double x)
{
  if (x <= 0) return 0.0;
  const double lga = std::lgamma(a);
  if (x < a + 1)
  {
    // Series: P = e^{-x} x^a / Gamma(a+1) * sum_n x^n / ((a+1)...(a+n)).
    double term = 1.0 / a, sum = term;
    for (int n = 1; n < 1000; ++n)
    {
      term *= x / (a + n);
      sum += term;
      if (std::abs(term) < std::abs(sum) * 1e-15) break;
    }
    return sum * std::exp(-x + a * std::log(x) - lga);
  }
  // Continued fraction for Q = 1 - P (modified Lentz).
  const double tiny = 1e-300;
  double b = x + 1 - a, c = 1 / tiny, d = 1 / b, h = d;
  for (int i = 1; i < 1000; ++i)
  {
    const double an = -i * (i - a);
    b += 2;
    d = an * d + b;
    if (std::abs(d) < tiny) d = tiny;
    c = b + an / c;
    if (std::abs(c) < tiny) c = tiny;
    d = 1 / d;
    const double del = d * c;
    h *= del;
    if (std::abs(del - 1) < 1e-15) break;
  }
  return 1.0 - std::exp(-x + a * std::log(x) - lga) * h;
}

double chi2Cdf(double x, int dof) { return regularizedGammaP(0.5 * dof, 0.5 * x); }

double chi2Quantile(double p, int dof)
{
  if (!(p > 0 && p < 1) || dof < 1)
    throw std::invalid_argument("chi2Quantile: need 0 < p < 1 and dof >= 1");
  if (dof == 2) return -2.0 * std::log1p(-p);
  // Bracket then bisect: the CDF is monotone, 200 halvings reach double precision.
  double lo = 0, hi = dof + 10.0 * std::sqrt(2.0 * dof) + 10;
  while (chi2Cdf(hi, dof) < p) hi *= 2;
  for (int i = 0; i < 200 && hi - lo > 1e-13 * hi; ++i)
  {
    const double mid = 0.5 * (lo + hi);
    (chi2Cdf(mid, dof) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}
}  // namespace immslam::math
