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
    : m_pi(transition), m_piStep(transition), m_mu(prior), m_muPred(prior), m_floor(floor)
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
  m_alias.assign(r, -1);
  m_scratch.resize(r);
  m_mixW = MatX::Identity(r, r);
}

void CIMMEstimator::setAllModes(const VecX& x, const MatX& P)
{
  for (auto& m : m_modes) m = TGaussian{x, P};
  std::fill(m_alias.begin(), m_alias.end(), -1);
  m_numAliased = 0;
}

TGaussian& CIMMEstimator::mode(int i)
{
  if (m_numAliased.load() > 0)
  {
    const std::lock_guard<std::mutex> lock(m_aliasMutex);
    unalias(i);
    for (int j = 0; j < numModels(); ++j)
      if (m_alias[j] == i) unalias(j);  // they keep the covariance mode i has now
  }
  return m_modes[i];
}

void CIMMEstimator::unalias(int i)
{
  const int s = m_alias[i];
  if (s < 0) return;
  m_modes[i].x = m_modes[s].x;
  m_modes[i].P = m_modes[s].P;
  m_alias[i] = -1;
  --m_numAliased;
}

void CIMMEstimator::aliasMode(int i, int source)
{
  const int r = numModels();
  if (i < 0 || i >= r || source < 0 || source >= r) throw std::out_of_range("IMM::aliasMode: no such mode");
  const std::lock_guard<std::mutex> lock(m_aliasMutex);
  source = root(source);
  if (source == i) return;  // already mode i's own covariance
  for (int j = 0; j < r; ++j)
    if (m_alias[j] == i) unalias(j);  // they keep mode i's current covariance
  if (m_alias[i] < 0) ++m_numAliased;
  m_alias[i] = source;
  m_modes[i].x = m_modes[source].x;
}

MatX CIMMEstimator::transitionOver(double steps) const
{
  if (!(steps >= 0) || !std::isfinite(steps))
  {
    std::ostringstream s;
    s << "IMM: the interval of a transition must be a finite number of steps >= 0, got " << steps;
    throw std::invalid_argument(s.str());
  }
  if (steps == 1.0) return m_pi;
  const Eigen::Index r = m_pi.rows();
  const double whole = std::floor(steps), f = steps - whole;
  // pi^n by squaring (n <= 2^53: at most ~106 products of r x r matrices).
  MatX result = MatX::Identity(r, r), base = m_pi;
  for (double n = whole; n >= 1; n = std::floor(n / 2))
  {
    if (std::fmod(n, 2.0) == 1.0) result = result * base;
    if (n >= 2) base = base * base;
  }
  if (f > 0) result = result * ((1.0 - f) * MatX::Identity(r, r) + f * m_pi);
  // Rows of a product of stochastic matrices sum to 1 up to rounding; renormalize that rounding away.
  for (Eigen::Index j = 0; j < r; ++j) result.row(j) /= result.row(j).sum();
  return result;
}

void CIMMEstimator::mix(math::CThreadPool* pool, double steps, const std::vector<char>* lowerOnly)
{
  if (lowerOnly && static_cast<int>(lowerOnly->size()) != numModels())
    throw std::invalid_argument("IMM::mix: one lower-triangle flag per mode");
  const int r = numModels();
  m_piStep = transitionOver(steps);
  const MatX& pi = m_piStep;
  // mu_{k|k-1}^i = sum_j pi_ji mu^j (eq. 7)
  m_muPred = pi.transpose() * m_mu;
  for (int i = 0; i < r; ++i)
    for (int j = 0; j < r; ++j)
      m_mixW(j, i) = m_muPred[i] > 0 ? pi(j, i) * m_mu[j] / m_muPred[i] : (i == j ? 1.0 : 0.0);
  if (r == 1) return;

  // Inputs: mode j's Gaussian is in(j), its own or the one it shares (aliasMode()); outputs go to
  // each mode's own storage. A shared covariance is read once per column for all the modes sharing it.
  const auto in = [this](int j) -> const TGaussian& { return m_modes[root(j)]; };
  const Eigen::Index n = m_modes[0].x.size();
  for (int j = 0; j < r; ++j)
    if (in(j).x.size() != n || in(j).P.rows() != n || in(j).P.cols() != n)
      throw std::logic_error("IMM::mix: modes have different dimensions");

  splitMixingWeights(pi);
  const int nGroups = static_cast<int>(m_mixSupp.size());
  const bool common = nGroups > 0;
  mixMeans(n);
  const bool inplace = prepareMixOutputs(n);

  // Covariances, by chunks of 16 columns: column c of every output, rows [c, n) (lower triangle,
  // every access sequential), then the chunk's rows of the upper triangle copied from its own lower
  // columns (exactly symmetric whatever the inputs' rounding). A chunk writes the lower part of its
  // columns and the upper part of its rows: disjoint from every other chunk, and the arithmetic of a
  // column does not depend on the chunk or the thread, so the result is bitwise the same for any pool.
  constexpr Eigen::Index chunk = 16;
  const int nChunks = static_cast<int>((n + chunk - 1) / chunk);
  if (common) m_mixU.resize(n, static_cast<Eigen::Index>(nChunks) * nGroups);  // one column per chunk and group
  auto job = [&](int t) {
    const Eigen::Index c0 = static_cast<Eigen::Index>(t) * chunk, c1 = std::min(n, c0 + chunk);
    for (Eigen::Index col = c0; col < c1; ++col) mixColumn(n, col, t, nGroups, inplace);
    mirrorChunk(n, c0, c1, inplace, lowerOnly);
  };
  if (pool)
    pool->parallelFor(0, nChunks, job);
  else
    for (int t = 0; t < nChunks; ++t) job(t);

  for (int i = 0; i < r; ++i)
  {
    m_modes[i].x = m_mixXbar.col(i);
    if (!inplace) std::swap(m_modes[i].P, m_scratch[i]);
  }
  std::fill(m_alias.begin(), m_alias.end(), -1);  // every output is in its own storage
  m_numAliased = 0;
}

void CIMMEstimator::splitMixingWeights(const MatX& pi)
{
  const int r = numModels();
  // Split of the weights: W_ji = (beta_i + Delta_ji) mu^j / c_i over the support J_i = {j: pi_ji > 0}
  // with beta_i = min_{j in J_i} pi_ji (the column minimum, diagonal included, when the column has no
  // zero) and Delta_ji = pi_ji - beta_i >= 0. m_mixB[i] = beta_i / c_i weighs the common term of J_i,
  // S_J + T_J, m_mixA(j, i) = Delta_ji mu^j / c_i mode j's own term. A mode with c_i = 0 keeps its
  // Gaussian (identity column of W): its B and A stay 0. Outputs with the same support share one
  // common term (one group for a pi without zeros).
  m_mixA.setZero(r, r);
  m_mixB.setZero(r);
  m_mixGroup.assign(r, -1);
  m_mixSupp.clear();
  std::vector<char> supp(r);
  for (int i = 0; i < r; ++i)
  {
    if (!(m_muPred[i] > 0)) continue;
    double beta = 0;
    for (int j = 0; j < r; ++j)
    {
      supp[j] = pi(j, i) > 0 ? 1 : 0;
      if (supp[j] && (beta == 0 || pi(j, i) < beta)) beta = pi(j, i);
    }
    m_mixB[i] = beta / m_muPred[i];
    // Entries equal up to rounding (a matrix read from an ini and renormalized) count as equal: a
    // Delta_ji of a few ulps would only cost an own term (and the in-place mixing).
    for (int j = 0; j < r; ++j)
      if (m_mu[j] > 0 && supp[j] && pi(j, i) - beta > 1e-12 * beta)
        m_mixA(j, i) = (pi(j, i) - beta) * m_mu[j] / m_muPred[i];
    if (!(m_mixB[i] > 0)) continue;
    const auto g = std::find(m_mixSupp.begin(), m_mixSupp.end(), supp);
    m_mixGroup[i] = static_cast<int>(g - m_mixSupp.begin());
    if (g == m_mixSupp.end()) m_mixSupp.push_back(supp);
  }
}

void CIMMEstimator::mixMeans(Eigen::Index n)
{
  const int r = numModels();
  const int nGroups = static_cast<int>(m_mixSupp.size());
  const auto in = [this](int j) -> const TGaussian& { return m_modes[root(j)]; };
  // Means. xbar^i = sum_j W_ji x^j (as the textbook); the spreads are expanded around
  // xm = sum_j mu^j x^j: y_j = x^j - xm and ybar_i = sum_j W_ji y_j (= xbar^i - xm), differences.
  m_mixXm.setZero(n);
  for (int j = 0; j < r; ++j)
    if (m_mu[j] > 0) m_mixXm.noalias() += m_mu[j] * in(j).x;
  m_mixY.resize(n, r);
  m_mixMuYT.resize(r, n);
  for (int j = 0; j < r; ++j)
  {
    m_mixY.col(j) = in(j).x - m_mixXm;
    m_mixMuYT.row(j) = m_mu[j] * m_mixY.col(j).transpose();
  }
  // A group whose support is every input uses m_mixMuYT itself; others a copy with the rows outside it zero.
  m_mixMuYTg.resize(nGroups);
  for (int g = 0; g < nGroups; ++g)
    if (std::find(m_mixSupp[g].begin(), m_mixSupp[g].end(), 0) != m_mixSupp[g].end())
    {
      m_mixMuYTg[g] = m_mixMuYT;
      for (int j = 0; j < r; ++j)
        if (!m_mixSupp[g][j]) m_mixMuYTg[g].row(j).setZero();
    }
    else
      m_mixMuYTg[g].resize(0, 0);
  m_mixXbar.setZero(n, r);
  m_mixYbar.setZero(n, r);
  for (int i = 0; i < r; ++i)
    for (int j = 0; j < r; ++j)
      if (m_mixW(j, i) > 0)
      {
        m_mixXbar.col(i).noalias() += m_mixW(j, i) * in(j).x;
        m_mixYbar.col(i).noalias() += m_mixW(j, i) * m_mixY.col(j);
      }
}

bool CIMMEstimator::prepareMixOutputs(Eigen::Index n)
{
  const int r = numModels();
  // In place when every output's own terms come from its own input only (A diagonal: pi = a I + b 1 1^T,
  // the default bank): column col of P^i is read (for u and for output i) before it is overwritten, and
  // the upper triangle, rewritten by the mirror, is never read. Otherwise into m_scratch, then swapped.
  bool inplace = true;
  for (int i = 0; i < r && inplace; ++i)
    for (int j = 0; j < r && inplace; ++j) inplace = j == i || !(m_mixA(j, i) > 0);
  if (!inplace)
    for (int i = 0; i < r; ++i) m_scratch[i].resize(n, n);
  // In place, a mode sharing another's covariance writes its output into its own storage before the
  // owner overwrites the column they both read: sharing modes first. One the mixing leaves untouched
  // (c_i = 0) gets its own copy now.
  m_mixOrder.clear();
  for (int i = 0; i < r; ++i)
    if (m_alias[i] >= 0)
    {
      if (inplace && !(m_muPred[i] > 0))
        unalias(i);
      else
        m_mixOrder.push_back(i);
    }
  for (int i = 0; i < r; ++i)
    if (m_alias[i] < 0) m_mixOrder.push_back(i);
  for (int i = 0; i < r; ++i)
    if (m_modes[i].P.rows() != n || m_modes[i].P.cols() != n) m_modes[i].P.resize(n, n);  // (stale storage)
  return inplace;
}

void CIMMEstimator::mixColumn(Eigen::Index n, Eigen::Index col, int t, int nGroups, bool inplace)
{
  const int r = numModels();
  const auto in = [this](int j) -> const TGaussian& { return m_modes[root(j)]; };
  const Eigen::Index h = n - col;
  // u_g = (S_J + T_J)(col:n, col) = sum_{j in J} mu^j (y_j y_j(col) + P^j(:, col))
  for (int g = 0; g < nGroups; ++g)
  {
    Eigen::Map<VecX> u(m_mixU.col(static_cast<Eigen::Index>(t) * nGroups + g).data() + col, h);
    const MatX& muYT = m_mixMuYTg[g].size() ? m_mixMuYTg[g] : m_mixMuYT;
    u.noalias() = m_mixY.bottomRows(h) * muYT.col(col);
    for (int j = 0; j < r; ++j)
      if (m_mu[j] > 0 && m_mixSupp[g][j]) u += m_mu[j] * in(j).P.col(col).tail(h);
  }
  for (const int i : m_mixOrder)
  {
    const int grp = m_mixGroup[i];
    Eigen::Map<VecX> u(grp >= 0 ? m_mixU.col(static_cast<Eigen::Index>(t) * nGroups + grp).data() + col : nullptr,
                       grp >= 0 ? h : 0);
    auto o = (inplace ? m_modes[i].P : m_scratch[i]).col(col).tail(h);
    if (!(m_muPred[i] > 0))
    {
      if (!inplace) o = in(i).P.col(col).tail(h);
      continue;
    }
    // o = B_i u + sum_{j: A_ji > 0} A_ji (P^j(:, col) + y_j y_j(col)) - ybar_i ybar_i(col),
    // the first of mode i's own terms fused with the common one (one pass for pi = a I + b 1 1^T).
    const auto yb = m_mixYbar.col(i).tail(h);
    const double ybc = m_mixYbar(col, i), b = m_mixB[i];
    int j = 0;
    while (j < r && !(m_mixA(j, i) > 0)) ++j;
    if (j == r)
    {
      if (b > 0)
        o = b * u - yb * ybc;
      else
        o = -(yb * ybc);
      continue;
    }
    {
      const double a = m_mixA(j, i);
      const auto Pj = in(j).P.col(col).tail(h);
      const auto y = m_mixY.col(j).tail(h);
      if (b > 0)
        o = b * u + a * Pj + (a * m_mixY(col, j)) * y - yb * ybc;
      else
        o = a * Pj + (a * m_mixY(col, j)) * y - yb * ybc;
    }
    for (++j; j < r; ++j)
    {
      const double a = m_mixA(j, i);
      if (a > 0) o += a * in(j).P.col(col).tail(h) + (a * m_mixY(col, j)) * m_mixY.col(j).tail(h);
    }
  }
}

void CIMMEstimator::mirrorChunk(Eigen::Index n, Eigen::Index c0, Eigen::Index c1, bool inplace,
                                const std::vector<char>* lowerOnly)
{
  const int r = numModels();
  // Mirror: rows [c0, c1) of the upper triangle (columns > row) from this chunk's lower columns.
  // The destination is 16 doubles per column, n doubles apart: no hardware prefetcher follows
  // that, so its cache lines are requested a few columns ahead (mix ~10 % faster measured at n = 613).
  for (int i = 0; i < r; ++i)
  {
    if (inplace && !(m_muPred[i] > 0)) continue;  // untouched
    if (lowerOnly && (*lowerOnly)[i] && m_muPred[i] > 0) continue;  // the caller mirrors
    double* S = (inplace ? m_modes[i].P : m_scratch[i]).data();
    for (Eigen::Index k = c0 + 1; k < n; ++k)
    {
#if defined(__GNUC__) || defined(__clang__)
      constexpr Eigen::Index ahead = 4;
      if (k + ahead < n)
        for (Eigen::Index a = c0; a < c1 + 7; a += 8) __builtin_prefetch(S + std::min(a, c1 - 1) + (k + ahead) * n, 1);
#endif
      const Eigen::Index e = std::min(k, c1);
      for (Eigen::Index a = c0; a < e; ++a) S[a + k * n] = S[k + a * n];
    }
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
  const Eigen::Index n = mode(0).x.size();
  x = VecX::Zero(n);
  for (int i = 0; i < r; ++i)
    if (w[i] > 0) x.noalias() += w[i] * mode(i).x;
  if (!P) return;
  MatX D = MatX::Zero(n, r);
  for (int i = 0; i < r; ++i)
    if (w[i] > 0) D.col(i) = std::sqrt(w[i]) * (mode(i).x - x);
  P->resize(n, n);
  constexpr int bw = 32;
  const int nTiles = static_cast<int>((n + bw - 1) / bw);
  auto tile = [&](int t) {
    const Eigen::Index c0 = static_cast<Eigen::Index>(t) * bw;
    const Eigen::Index cw = std::min<Eigen::Index>(bw, n - c0);
    auto out = P->middleCols(c0, cw);
    out.noalias() = D * D.middleRows(c0, cw).transpose();
    for (int i = 0; i < r; ++i)
      if (w[i] > 0) out += w[i] * mode(i).P.middleCols(c0, cw);
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
    const VecX d = mode(i).x.segment(off, len) - xComb.segment(off, len);
    B += w[i] * (mode(i).P.block(off, off, len, len) + d * d.transpose());
  }
  return B;
}
MatX CIMMEstimator::combinedColumns(const VecX& w, const VecX& xComb, int off, int len) const
{
  MatX C = MatX::Zero(xComb.size(), len);
  for (int i = 0; i < numModels(); ++i)
  {
    if (!(w[i] > 0)) continue;
    const VecX d = mode(i).x - xComb;
    C += w[i] * mode(i).P.middleCols(off, len);
    C.noalias() += (w[i] * d) * d.segment(off, len).transpose();
  }
  return C;
}
}  // namespace immslam::bayes
