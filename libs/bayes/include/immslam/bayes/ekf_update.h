/* imm-monoslam — the covariance algebra of the EKF, in one stateless place (OpenVINS'
 * StateHelper idea): updaters only build small Jacobian blocks over the variables they touch. */
#pragma once

#include <immslam/math/types.h>

#include <Eigen/Cholesky>

#include <vector>

namespace immslam::bayes
{
/** A sparse measurement Jacobian H (m x n) stored as dense blocks: block b covers rows
 * [row, row + J.rows()) and columns [col, col + J.cols()). Blocks may share rows (e.g. the
 * camera part and the feature part of one measurement); they must not overlap. */
class CSparseJacobian
{
 public:
  struct TBlock
  {
    int row = 0, col = 0;
    MatX J;
  };

  CSparseJacobian() = default;
  CSparseJacobian(int rows, int cols) : m_rows(rows), m_cols(cols) {}

  void resize(int rows, int cols);
  void clear() { m_blocks.clear(); }
  void addBlock(int row, int col, const MatX& J);

  int rows() const { return m_rows; }
  int cols() const { return m_cols; }
  const std::vector<TBlock>& blocks() const { return m_blocks; }

  /** P H^T (n x m) for a symmetric P (n x n): cost O(n * sum of block sizes). */
  MatX timesTransposedBy(const Eigen::Ref<const MatX>& P) const;
  /** H M for M (n x k). */
  MatX times(const Eigen::Ref<const MatX>& M) const;
  /** H x. */
  VecX timesVector(const Eigen::Ref<const VecX>& x) const;
  /** The dense H (tests, debugging). */
  MatX toDense() const;

 private:
  int m_rows = 0, m_cols = 0;
  std::vector<TBlock> m_blocks;
};

/** Outcome of one EKF update. */
struct TUpdateResult
{
  bool ok = false;             ///< false if S was not positive definite (state left unchanged)
  int dim = 0;                 ///< number of scalar measurements
  double logLikelihood = 0;    ///< \f$ \ln \mathcal{N}(\nu; 0, S) \f$ (IMM paper eq. 3)
  double nis = 0;              ///< \f$ \nu^\top S^{-1} \nu \f$
};

/** What ekfLogLikelihood() computes and ekfUpdate() needs again: \f$ PH^\top \f$ and the Cholesky
 * factor of \f$ S = HPH^\top + R \f$. Valid only for the same P, H and R (the caller's contract);
 * ekfUpdate() consumes it (ok = false afterwards). */
struct TInnovationFactors
{
  MatX PHt;
  Eigen::LLT<MatX> llt;
  bool ok = false;
};

/** Kalman update of (x, P) with innovation nu = z - h(x), sparse Jacobian H and measurement noise R:
 * \f$ S = H P H^\top + R,\; K = P H^\top S^{-1},\; x \mathrel{+}= K\nu,\;
 * P \mathrel{-}= (PH^\top) S^{-1} (PH^\top)^\top \f$, the last as a symmetric rank-m update
 * (only one triangle computed, then mirrored: P stays exactly symmetric).
 * \param Rdiag the diagonal of R (independent pixel noise).
 * \param reuse if given and ok: the factors ekfLogLikelihood() kept for this P, H and R (the O(n m k)
 * product and the O(m^3) factorisation are not repeated; the result is bitwise the same). */
TUpdateResult ekfUpdate(VecX& x, MatX& P, const CSparseJacobian& H, const VecX& nu, const VecX& Rdiag,
                        TInnovationFactors* reuse = nullptr);

/** The log-likelihood \f$ \ln \mathcal{N}(\nu; 0, H P H^\top + R) \f$ and NIS of the innovation, without
 * updating (x, P): the same numbers ekfUpdate() reports, at O(n * sum of block sizes + m^3) instead of
 * the update's O(n^2 m). Used for the IMM modes that are not updated in a frame (see
 * CMonoSlamIMM, dormant modes). \param x if given, the mean update only: x += P H^T S^-1 nu (O(n m)).
 * \param keep if given, receives P H^T and the factor of S for a later ekfUpdate() of the same P, H, R.
 * \return ok = false if S is not positive definite (x left unchanged). */
TUpdateResult ekfLogLikelihood(const MatX& P, const CSparseJacobian& H, const VecX& nu, const VecX& Rdiag,
                               VecX* x = nullptr, TInnovationFactors* keep = nullptr);

/** Innovation covariance \f$ H P H^\top + R \f$ only (no update). */
MatX innovationCovariance(const MatX& P, const CSparseJacobian& H, const VecX& Rdiag);
}  // namespace immslam::bayes
