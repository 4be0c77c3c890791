/* imm-monoslam — Umeyama's least-squares similarity between point sets.
 *
 * Derivation (our own, following the structure of Umeyama 1991): for fixed R and s the optimal t is
 * mu_d - s R mu_s, which reduces the cost to
 *   sum |y_i - s R x_i|^2 = n (sigma_d^2 - 2 s tr(R^T Sigma) + s^2 sigma_s^2),
 * with centred x_i = s_i - mu_s, y_i = d_i - mu_d and Sigma = (1/n) sum y_i x_i^T. R must maximize
 * tr(R^T Sigma) = tr(R^T U D V^T) = tr(D (U^T R V)); with Z = U^T R V orthogonal of det(U)det(V)
 * det(R), tr(D Z) <= sum d_k with equality at Z = I when det(U)det(V) = +1; otherwise the best
 * proper choice flips the direction of the smallest singular value: Z = diag(1, 1, -1). Finally
 * d cost/ds = 0 gives s = tr(R^T Sigma) / sigma_s^2 = tr(D S) / sigma_s^2.
 */
#include <immslam/eval/alignment.h>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <cmath>
#include <stdexcept>

namespace immslam::eval
{
const char* alignmentName(EAlignment a)
{
  switch (a)
  {
    case EAlignment::Sim3:
      return "Sim3";
    case EAlignment::SE3:
      return "SE3";
    case EAlignment::None:
      return "None";
  }
  return "?";
}

TSim3 TSim3::inverse() const
{
  TSim3 inv;
  inv.s = 1.0 / s;
  inv.R = R.transpose();
  inv.t = -(inv.s * (inv.R * t));
  return inv;
}

TSim3 TSim3::operator*(const TSim3& o) const
{
  // this(o(x)) = s R (o.s o.R x + o.t) + t
  TSim3 c;
  c.s = s * o.s;
  c.R = R * o.R;
  c.t = s * (R * o.t) + t;
  return c;
}

TSim3 alignUmeyama(const std::vector<Vec3>& src, const std::vector<Vec3>& dst, bool withScale, int* rank)
{
  if (src.size() != dst.size())
    throw std::invalid_argument("alignUmeyama: src has " + std::to_string(src.size()) +
                                " points, dst has " + std::to_string(dst.size()));
  const size_t n = src.size();
  for (size_t i = 0; i < n; ++i)
    if (!src[i].allFinite() || !dst[i].allFinite())
      throw std::invalid_argument("alignUmeyama: point " + std::to_string(i) + " is not finite");
  if (rank) *rank = 0;
  if (n == 0) return TSim3{};

  Vec3 muS = Vec3::Zero(), muD = Vec3::Zero();
  double maxS = 0, maxD = 0;
  for (size_t i = 0; i < n; ++i)
  {
    muS += src[i];
    muD += dst[i];
    maxS = std::max(maxS, src[i].cwiseAbs().maxCoeff());
    maxD = std::max(maxD, dst[i].cwiseAbs().maxCoeff());
  }
  muS /= static_cast<double>(n);
  muD /= static_cast<double>(n);
  double varS = 0, varD = 0;
  Mat3 Sigma = Mat3::Zero();
  for (size_t i = 0; i < n; ++i)
  {
    const Vec3 x = src[i] - muS, y = dst[i] - muD;
    varS += x.squaredNorm();
    varD += y.squaredNorm();
    Sigma += y * x.transpose();
  }
  varS /= static_cast<double>(n);
  varD /= static_cast<double>(n);
  Sigma /= static_cast<double>(n);

  // Rank 0: one of the sets is a single point (up to rounding), or Sigma vanishes.
  TSim3 translationOnly;
  translationOnly.t = muD - muS;
  const double rel = 1e-12;
  if (std::sqrt(varS) <= rel * maxS || std::sqrt(varD) <= rel * maxD) return translationOnly;

  const Eigen::JacobiSVD<Mat3> svd(Sigma, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Vec3 d = svd.singularValues();  // descending
  if (d[0] <= rel * std::sqrt(varS * varD)) return translationOnly;
  const double tol = 1e-10 * d[0];
  const int r = 1 + (d[1] > tol ? 1 : 0) + (d[2] > tol ? 1 : 0);
  if (rank) *rank = r;

  const Mat3& U = svd.matrixU();
  const Mat3& V = svd.matrixV();
  TSim3 out;
  if (r == 1)
  {
    // Collinear: any R with R v1 = u1 is optimal; take the smallest such rotation.
    out.R = Eigen::Quaterniond::FromTwoVectors(V.col(0), U.col(0)).toRotationMatrix();
  }
  else
  {
    Vec3 S(1, 1, 1);
    if (U.determinant() * V.determinant() < 0) S[2] = -1;
    out.R = U * S.asDiagonal() * V.transpose();
  }
  // s = tr(R^T Sigma) / sigma_s^2 (= tr(D S) / sigma_s^2 in the general case).
  out.s = withScale ? (out.R.transpose() * Sigma).trace() / varS : 1.0;
  out.t = muD - out.s * (out.R * muS);
  return out;
}
}  // namespace immslam::eval
