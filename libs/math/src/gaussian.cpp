/* imm-monoslam — Gaussian likelihoods computed stably in log space. */
#include <immslam/math/gaussian.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <limits>

namespace immslam::math
{
double gaussianLogLikelihood(const VecX& nu, const MatX& S, double* mahalanobis2Out)
{
  const Eigen::LLT<MatX> llt(S);
  if (llt.info() != Eigen::Success)
  {
    if (mahalanobis2Out) *mahalanobis2Out = std::numeric_limits<double>::infinity();
    return -std::numeric_limits<double>::infinity();
  }
  const VecX z = llt.matrixL().solve(nu);
  const double d2 = z.squaredNorm();
  // ln|S| = 2 sum ln L_ii
  const double logDet = 2.0 * llt.matrixLLT().diagonal().array().log().sum();
  if (mahalanobis2Out) *mahalanobis2Out = d2;
  return -0.5 * (d2 + logDet + static_cast<double>(nu.size()) * std::log(2.0 * M_PI));
}

double mahalanobis2(const VecX& nu, const MatX& S)
{
  double d2 = 0;
  gaussianLogLikelihood(nu, S, &d2);
  return d2;
}

double logSumExp(const VecX& v)
{
  if (v.size() == 0) return -std::numeric_limits<double>::infinity();
  const double m = v.maxCoeff();
  if (!std::isfinite(m)) return m;
  return m + std::log((v.array() - m).exp().sum());
}

void symmetrize(MatX& P)
{
  // In place, upper triangle mirrored from the average (no temporary of full size).
  for (Eigen::Index j = 0; j < P.cols(); ++j)
    for (Eigen::Index i = j + 1; i < P.rows(); ++i)
    {
      const double a = 0.5 * (P(i, j) + P(j, i));
      P(i, j) = a;
      P(j, i) = a;
    }
}
}  // namespace immslam::math
