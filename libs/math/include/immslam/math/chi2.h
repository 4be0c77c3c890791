/* imm-monoslam — chi-square distribution (exact, not mrpt::math::chi2inv's approximation). */
#pragma once

namespace immslam::math
{
/** Regularized lower incomplete gamma function P(a, x). */
double regularizedGammaP(double a, double x);

/** CDF of the chi-square distribution with dof degrees of freedom. */
double chi2Cdf(double x, int dof);

/** Quantile: the x with chi2Cdf(x, dof) = p, for 0 < p < 1 and dof >= 1.
 * For dof = 2 this is exactly -2 ln(1-p) (5.991 for p = 0.95). */
double chi2Quantile(double p, int dof);
}  // namespace immslam::math
