/* imm-monoslam — generic Interacting Multiple Model estimator (IMM paper Fig. 2). */
#include <immslam/bayes/CIMMEstimator.h>
#include <immslam/math/gaussian.h>
#include <immslam/math/parallel.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace immslam::bayes
{
CIMMEstimator::CIMMEstimator(const MatX& transition, const VecX& prior, double floor)
    : m_pi(transition), m_mu(prior), m_muPred(prior), m_floor(floor)
{
  const auto r = prior.size();
  if (r < 1 || transition.rows() != r || transition.cols() != r)
    throw std::invalid_argument("IMM: transition matrix must be r x r with r = number of prior probabilities");
  if (!(floor >= 0) || floor * r >= 1) throw std::invalid_argument("IMM: probability floor must be in [0, 1/r)");
  for (int j = 0; j < r; ++j)
  {
    if (!(m_pi.row(j).array() >= 0).all())
    {
      std::ostringstream s;
      s << "IMM: transition matrix row " << j << " has a negative or NaN entry";
      throw std::invalid_argument(s.str());
    }
    if (std::abs(m_pi.row(j).sum() - 1.0) > 1e-9)
    {
      std::ostringstream s;
      s << "IMM: transition matrix row " << j << " sums to " << m_pi.row(j).sum() << ", not 1";
      throw std::invalid_argument(s.str());
    }
  }
  if (!(m_mu.array() >= 0).all() || std::abs(m_mu.sum() - 1.0) > 1e-9)
    throw std::invalid_argument("IMM: prior model probabilities must be >= 0 and sum to 1");
  m_modes.resize(r);
  m_scratch.resize(r);
  m_mixW = MatX::Identity(r, r);
}

void CIMMEstimator::setAllModes(const VecX& x, const MatX& P)
{
  for (auto& m : m_modes) m = TGaussian{x, P};
}

void CIMMEstimator::mix(math::CThreadPool* pool)
{
  const int r = numModels();
  // mu_{k|k-1}^i = sum_j pi_ji mu^j (eq. 7)
  m_muPred = m_pi.transpose() * m_mu;
  for (int i = 0; i < r; ++i)
    for (int j = 0; j < r; ++j)
      m_mixW(j, i) = m_muPred[i] > 0 ? m_pi(j, i) * m_mu[j] / m_muPred[i] : (i == j ? 1.0 : 0.0);
  if (r == 1) return;

  const Eigen::Index n = m_modes[0].x.size();
  for (const auto& m : m_modes)
    if (m.x.size() != n || m.P.rows() != n || m.P.cols() != n)
      throw std::logic_error("IMM::mix: modes have different dimensions");

  // Mixed means and the spread factors D_i = [sqrt(mu^{j|i}) (x^j - xbar^i)]_j, so that
  // sum_j mu^{j|i} (x^j - xbar^i)(...)^T = D_i D_i^T.
  std::vector<VecX> xbar(r);
  std::vector<MatX> D(r);
  for (int i = 0; i < r; ++i)
  {
    xbar[i] = VecX::Zero(n);
    for (int j = 0; j < r; ++j)
      if (m_mixW(j, i) > 0) xbar[i].noalias() += m_mixW(j, i) * m_modes[j].x;
    D[i] = MatX::Zero(n, r);
    for (int j = 0; j < r; ++j)
      if (m_mixW(j, i) > 0) D[i].col(j) = std::sqrt(m_mixW(j, i)) * (m_modes[j].x - xbar[i]);
  }
  for (int i = 0; i < r; ++i) m_scratch[i].resize(n, n);

  // Tiles of columns [c0, c0 + bw), rows [c0, n): lower triangle (incl. diagonal tiles).
  constexpr int bw = 16;
  const int nTiles = static_cast<int>((n + bw - 1) / bw);
  auto tile = [&](int t) {
    const Eigen::Index c0 = static_cast<Eigen::Index>(t) * bw;
    const Eigen::Index w = std::min<Eigen::Index>(bw, n - c0);
    const Eigen::Index h = n - c0;
    for (int i = 0; i < r; ++i)
    {
      auto out = m_scratch[i].block(c0, c0, h, w);
      out.noalias() = D[i].bottomRows(h) * D[i].middleRows(c0, w).transpose();
      for (int j = 0; j < r; ++j)
        if (m_mixW(j, i) > 0) out += m_mixW(j, i) * m_modes[j].P.block(c0, c0, h, w);
    }
  };
  if (pool)
    pool->parallelFor(0, nTiles, tile);
  else
    for (int t = 0; t < nTiles; ++t) tile(t);

  for (int i = 0; i < r; ++i)
  {
    m_scratch[i].triangularView<Eigen::StrictlyUpper>() = m_scratch[i].transpose();
    m_modes[i].x = std::move(xbar[i]);
    std::swap(m_modes[i].P, m_scratch[i]);
  }
}

void CIMMEstimator::updateProbabilities(const VecX& logLik)
{
  const int r = numModels();
  if (logLik.size() != r) throw std::invalid_argument("IMM::updateProbabilities: one log-likelihood per model");
  VecX a(r);
  for (int i = 0; i < r; ++i)
  {
    const double l = std::isfinite(logLik[i]) ? logLik[i] : -std::numeric_limits<double>::infinity();
    a[i] = m_muPred[i] > 0 ? std::log(m_muPred[i]) + l : -std::numeric_limits<double>::infinity();
  }
  const double lse = math::logSumExp(a);
  if (!std::isfinite(lse))
    m_mu = m_muPred;
  else
    m_mu = (a.array() - lse).exp().matrix();
  // Floor, then renormalize so that every probability is >= floor and they sum to 1.
  if (m_floor > 0)
  {
    double excess = 0, freeMass = 0;
    for (int i = 0; i < r; ++i)
      if (m_mu[i] < m_floor)
        excess += m_floor - m_mu[i];
      else
        freeMass += m_mu[i] - m_floor;
    for (int i = 0; i < r; ++i)
      m_mu[i] = m_mu[i] < m_floor ? m_floor : m_mu[i] - (freeMass > 0 ? excess * (m_mu[i] - m_floor) / freeMass : 0);
  }
  m_mu /= m_mu.sum();
}

void CIMMEstimator::combine(const VecX& w, VecX& x, MatX* P, math::CThreadPool* pool) const
{
  const int r = numModels();
  const Eigen::Index n = m_modes[0].x.size();
  x = VecX::Zero(n);
  for (int i = 0; i < r; ++i)
    if (w[i] > 0) x.noalias() += w[i] * m_modes[i].x;
  if (!P) return;
  MatX D = MatX::Zero(n, r);
  for (int i = 0; i < r; ++i)
    if (w[i] > 0) D.col(i) = std::sqrt(w[i]) * (m_modes[i].x - x);
  P->resize(n, n);
  constexpr int bw = 32;
  const int nTiles = static_cast<int>((n + bw - 1) / bw);
  auto tile = [&](int t) {
    const Eigen::Index c0 = static_cast<Eigen::Index>(t) * bw;
    const Eigen::Index cw = std::min<Eigen::Index>(bw, n - c0);
    auto out = P->middleCols(c0, cw);
    out.noalias() = D * D.middleRows(c0, cw).transpose();
    for (int i = 0; i < r; ++i)
      if (w[i] > 0) out += w[i] * m_modes[i].P.middleCols(c0, cw);
  };
  if (pool)
    pool->parallelFor(0, nTiles, tile);
  else
    for (int t = 0; t < nTiles; ++t) tile(t);
}

MatX CIMMEstimator::combinedBlock(const VecX& w, const VecX& xComb, int off, int len) const
{
  MatX B = MatX::Zero(len, len);
  for (int i = 0; i < numModels(); ++i)
  {
    if (!(w[i] > 0)) continue;
    const VecX d = m_modes[i].x.segment(off, len) - xComb.segment(off, len);
    B += w[i] * (m_modes[i].P.block(off, off, len, len) + d * d.transpose());
  }
  return B;
}
MatX CIMMEstimator::combinedColumns(const VecX& w, const VecX& xComb, int off, int len) const
{
  MatX C = MatX::Zero(xComb.size(), len);
  for (int i = 0; i < numModels(); ++i)
  {
    if (!(w[i] > 0)) continue;
    const VecX d = m_modes[i].x - xComb;
    C += w[i] * m_modes[i].P.middleCols(off, len);
    C.noalias() += (w[i] * d) * d.segment(off, len).transpose();
  }
  return C;
}
}  // namespace immslam::bayes
