/* imm-monoslam — stateless EKF covariance algebra on sparse Jacobians. */
#include <immslam/bayes/ekf_update.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <stdexcept>

namespace immslam::bayes
{
void CSparseJacobian::resize(int rows, int cols)
{
  m_rows = rows;
  m_cols = cols;
  m_blocks.clear();
}

void CSparseJacobian::addBlock(int row, int col, const MatX& J)
{
  if (row < 0 || col < 0 || row + J.rows() > m_rows || col + J.cols() > m_cols)
    throw std::out_of_range("CSparseJacobian::addBlock: block outside the matrix");
  m_blocks.push_back({row, col, J});
}

namespace
{
/** out += A B^T for a 2 x C block B (the measurement blocks of one image point; C = 3 or 6 for the
 * features), coefficient-wise: a general product would pack both operands for a 2-column result. */
template <int C>
void addTimesTransposed2(Eigen::Ref<MatX> out, const Eigen::Ref<const MatX>& A, const MatX& B)
{
  const Eigen::Matrix<double, 2, C> Bf = B;
  out.noalias() += A.lazyProduct(Bf.transpose());
}
}  // namespace

MatX CSparseJacobian::timesTransposedBy(const Eigen::Ref<const MatX>& P) const
{
  MatX PHt = MatX::Zero(P.rows(), m_rows);
  for (const auto& b : m_blocks)
  {
    auto out = PHt.middleCols(b.row, b.J.rows());
    const auto A = P.middleCols(b.col, b.J.cols());
    if (b.J.rows() == 2 && b.J.cols() == 6)
      addTimesTransposed2<6>(out, A, b.J);
    else if (b.J.rows() == 2 && b.J.cols() == 3)
      addTimesTransposed2<3>(out, A, b.J);
    else
      out.noalias() += A * b.J.transpose();
  }
  return PHt;
}

MatX CSparseJacobian::times(const Eigen::Ref<const MatX>& M) const
{
  MatX out = MatX::Zero(m_rows, M.cols());
  for (const auto& b : m_blocks)
  {
    auto o = out.middleRows(b.row, b.J.rows());
    const auto A = M.middleRows(b.col, b.J.cols());
    if (b.J.rows() <= 2 && b.J.cols() <= 7)
      o.noalias() += b.J.lazyProduct(A);  // a few rows: no packing
    else
      o.noalias() += b.J * A;
  }
  return out;
}

VecX CSparseJacobian::timesVector(const Eigen::Ref<const VecX>& x) const
{
  VecX out = VecX::Zero(m_rows);
  for (const auto& b : m_blocks) out.segment(b.row, b.J.rows()).noalias() += b.J * x.segment(b.col, b.J.cols());
  return out;
}

MatX CSparseJacobian::toDense() const
{
  MatX H = MatX::Zero(m_rows, m_cols);
  for (const auto& b : m_blocks) H.block(b.row, b.col, b.J.rows(), b.J.cols()) += b.J;
  return H;
}

MatX innovationCovariance(const MatX& P, const CSparseJacobian& H, const VecX& Rdiag)
{
  MatX S = H.times(H.timesTransposedBy(P));
  S.diagonal() += Rdiag;
  return S;
}

namespace
{
/** P H^T and the Cholesky factor of S = H P H^T + R (symmetrised), the same arithmetic for the
 * likelihood and the update. \return false if S is not positive definite. */
bool innovationFactors(const MatX& P, const CSparseJacobian& H, const VecX& Rdiag, TInnovationFactors& f)
{
  f.PHt = H.timesTransposedBy(P);  // n x m
  MatX S = H.times(f.PHt);
  S = 0.5 * (S + S.transpose());
  S.diagonal() += Rdiag;
  f.llt.compute(S);
  f.ok = f.llt.info() == Eigen::Success;
  return f.ok;
}

double gaussianLogLikelihood(const TInnovationFactors& f, double nis, int dim)
{
  return -0.5 * (nis + 2.0 * f.llt.matrixLLT().diagonal().array().log().sum() + dim * std::log(2 * M_PI));
}
}  // namespace

TUpdateResult ekfLogLikelihood(const MatX& P, const CSparseJacobian& H, const VecX& nu, const VecX& Rdiag, VecX* x,
                               TInnovationFactors* keep)
{
  TUpdateResult res;
  res.dim = static_cast<int>(nu.size());
  if (keep) keep->ok = false;
  if (nu.size() == 0)
  {
    res.ok = true;
    return res;
  }
  TInnovationFactors local;
  TInnovationFactors& f = keep ? *keep : local;
  if (!innovationFactors(P, H, Rdiag, f)) return res;
  res.nis = f.llt.matrixL().solve(nu).squaredNorm();
  if (x) x->noalias() += f.PHt * f.llt.solve(nu);
  res.logLikelihood = gaussianLogLikelihood(f, res.nis, res.dim);
  res.ok = true;
  return res;
}

TUpdateResult ekfUpdate(VecX& x, MatX& P, const CSparseJacobian& H, const VecX& nu, const VecX& Rdiag,
                        TInnovationFactors* reuse)
{
  TUpdateResult res;
  res.dim = static_cast<int>(nu.size());
  const bool have = reuse && reuse->ok;
  if (reuse) reuse->ok = false;  // consumed: P changes below
  if (nu.size() == 0)
  {
    res.ok = true;
    return res;
  }
  TInnovationFactors local;
  TInnovationFactors& f = have ? *reuse : local;
  if (!have && !innovationFactors(P, H, Rdiag, f)) return res;
  // With S = L L^T: z = L^-1 nu, Z = L^-1 (P H^T)^T; then x += Z^T z, P -= Z^T Z.
  const auto L = f.llt.matrixL();
  const VecX z = L.solve(nu);
  MatX Z = f.PHt.transpose();
  L.solveInPlace(Z);
  res.nis = z.squaredNorm();
  res.logLikelihood = gaussianLogLikelihood(f, res.nis, res.dim);
  x.noalias() += Z.transpose() * z;
  P.selfadjointView<Eigen::Lower>().rankUpdate(Z.transpose(), -1.0);
  P.triangularView<Eigen::StrictlyUpper>() = P.transpose();
  res.ok = true;
  return res;
}
}  // namespace immslam::bayes
