/* imm-monoslam — central-difference Jacobians, used by the tests to check every analytic one. */
#pragma once

#include <immslam/math/types.h>

namespace immslam::math
{
/** Jacobian of f: R^n -> R^m at x by central differences with step eps (per coordinate). */
template <typename F>
MatX numericalJacobian(F&& f, const VecX& x, double eps = 1e-6)
{
  const VecX f0 = f(x);
  MatX J(f0.size(), x.size());
  for (int i = 0; i < x.size(); ++i)
  {
    VecX xp = x, xm = x;
    xp[i] += eps;
    xm[i] -= eps;
    J.col(i) = (f(xp) - f(xm)) / (2 * eps);
  }
  return J;
}
}  // namespace immslam::math
