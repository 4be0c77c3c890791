/* imm-monoslam — the Interacting Multiple Model estimator (IMM paper Sec. III, Figs. 1-2; Blom &
 * Bar-Shalom, the paper's ref. [1]). Generic: it knows nothing about cameras. It owns the r
 * mode-conditioned Gaussians (x^i, P^i), all of the same dimension and layout, the model
 * probabilities mu and the Markov transition matrix; the caller runs the mode-matched filters
 * (prediction and update of each (x^i, P^i)) between mix() and updateProbabilities(). */
#pragma once

#include <immslam/math/types.h>

#include <atomic>
#include <memory>
#include <mutex>
#include <vector>

namespace immslam::math
{
class CThreadPool;
}

namespace immslam::bayes
{
/** A mode-conditioned Gaussian. */
struct TGaussian
{
  VecX x;
  MatX P;
};

class CIMMEstimator
{
 public:
  /** \param transition Markov matrix pi (r x r), pi(j, i) = P(M_k = i | M_{k-1} = j): rows sum to 1.
   * \param prior initial model probabilities (sum 1). \param floor lower bound of every posterior
   * probability after each update (then renormalized), so no model dies for ever.
   * \throws std::invalid_argument if the sizes disagree, an entry is negative/NaN or a row does not
   * sum to 1 (1e-9). */
  CIMMEstimator(const MatX& transition, const VecX& prior, double floor = 1e-6);

  int numModels() const { return static_cast<int>(m_mu.size()); }

  /** The mode-conditioned states (all must keep the same dimension and layout). Write access
   * resolves the sharing of aliasMode() first (mode i gets its own copy, and the modes that share
   * mode i's covariance get theirs before it can change); read access does not copy. */
  TGaussian& mode(int i);
  const TGaussian& mode(int i) const { return m_modes[root(i)]; }
  /** Sets every mode to the same Gaussian (start-up). */
  void setAllModes(const VecX& x, const MatX& P);
  /** Mode i becomes an exact copy of mode `source` (mean and covariance), the covariance shared
   * instead of copied until someone writes to either mode (mode() above) or the next mix(), which
   * reads the shared covariance as mode i's input and writes mode i's output into mode i's own
   * storage. For a bank whose improbable modes take the posterior of a probable one every frame
   * (CMonoSlamIMM's dormant modes), that saves one n x n copy per such mode and frame (the mixing
   * reads a shared column once from memory, then from cache). The estimate is bitwise the same as
   * with a copy. Threads: write access to different modes may run concurrently (it locks while any
   * covariance is shared); a read of a mode must not run concurrently with aliasMode() or with a write
   * access that may resolve its sharing. */
  void aliasMode(int i, int source);
  /** True while mode i shares another mode's covariance (aliasMode()). */
  bool isAliased(int i) const { return m_alias[i] >= 0; }

  /** Posterior probabilities mu_{k|k} (after updateProbabilities), or mu_{k-1|k-1} before. */
  const VecX& probabilities() const { return m_mu; }
  /** mu_{k|k-1} = pi^T mu_{k-1|k-1} (Fig. 2 step 1, eq. 7), valid after mix(). */
  const VecX& predictedProbabilities() const { return m_muPred; }
  const MatX& transition() const { return m_pi; }

  /** IMM paper Fig. 2 step 1 (filter reinitialization): predicted probabilities
   * \f$ c_i = \mu^i_{k|k-1} = \sum_j \pi_{ji}\mu^j \f$, mixing weights
   * \f$ W_{ji} = \mu^{j|i} = \pi_{ji}\mu^j / c_i \f$ (identity column if c_i = 0: mode i kept as
   * it is), and every mode replaced by its mixed estimate and covariance
   * \f$ \bar x^i = \sum_j W_{ji} x^j \f$,
   * \f$ \bar P^i = \sum_j W_{ji} (P^j + (x^j - \bar x^i)(x^j - \bar x^i)^\top) \f$.
   *
   * Computed exactly (no approximation), for any Markov matrix, from the structure of pi: per column i,
   * beta_i = min_j pi_ji (diagonal included) and Delta_ji = pi_ji - beta_i >= 0. Expanded around
   * xm = sum_j mu^j x^j with y_j = x^j - xm and ybar_i = sum_j W_ji y_j (= xbar^i - xm; differences
   * of nearby means, so the sums below carry no large offsets), since sum_j W_ji = 1:
   * \f[ \bar P^i = \frac{\beta_i}{c_i}(S + T) + \sum_{j: \Delta_{ji} > 0} \frac{\Delta_{ji}\mu^j}{c_i}
   *     (P^j + y_j y_j^\top) - \bar y_i \bar y_i^\top, \qquad S = \sum_j \mu^j P^j,\;
   *     T = \sum_j \mu^j y_j y_j^\top \f]
   * S + T is shared by all outputs (skipped when every beta_i is 0; a column with beta_i = 0 skips
   * it). Where column i of pi has zeros (a mode that cannot be entered from some others), beta_i is the
   * minimum over its support J_i = {j : pi_ji > 0} and the common term is S_J + T_J, the same sums over
   * J_i only, computed once per distinct support: a block-structured pi (the shipped bank: no
   * transition from a still or rotating mode into a general one, doc/imm.md) keeps Delta diagonal and
   * the mixing in place. For the default pi = transition_stay on the diagonal, the rest even, Delta is diagonal: each
   * output is the common term plus its own mode. Rounding: the subtraction of ybar ybar^T costs
   * O(eps max_j |y_j|^2) absolutely, i.e. relative to the spread of the modes' means, not to |x|.
   * Cost O(r n^2) + O(nnz(Delta) n^2) flops (the direct sum is O(r^2 n^2)); memory: the lower
   * triangles of the r inputs read once, the r outputs written once: over their own inputs when Delta
   * is diagonal (the default pi: column col of P^i is read for S + T and for output i before it is
   * overwritten, the upper triangle is only written), else into separate buffers swapped in after.
   * Column chunk by column chunk: lower triangle of each column (sequential accesses), then the
   * chunk's rows of the upper triangle copied from it, so every output is exactly symmetric.
   * \param pool optional worker pool (chunks in parallel; bitwise the same result for any pool).
   * \param steps the time since the last update, in transition steps (frames): the Markov matrix of
   * the interval, transitionOver(steps), replaces pi above (a dropped or skipped frame leaves two steps
   * for the mode to switch in). 1 uses pi itself, bitwise.
   * \param lowerOnly optional, one flag per mode: the outputs flagged get only their lower triangle
   * (diagonal included); their strictly upper triangle is left stale. For a caller whose next step
   * reads the lower triangle only and mirrors itself (CMonoSlamIMM's mode predictions): the mirror
   * costs about 30 % of the mixing. */
  void mix(math::CThreadPool* pool = nullptr, double steps = 1.0, const std::vector<char>* lowerOnly = nullptr);

  /** The Markov matrix over an interval of `steps` transition steps: pi^n for a whole number n (by
   * squaring), and for a fraction f of a step the "lazy chain" (1 - f) I + f pi (the chain that takes
   * a step with probability f), so pi(n + f) = pi^n ((1 - f) I + f pi): a stochastic matrix for every
   * steps >= 0, continuous in steps, exact at whole numbers and the identity at 0.
   * \throws std::invalid_argument if steps is negative or not finite. */
  MatX transitionOver(double steps) const;
  /** The matrix the last mix() used (transitionOver(steps) of that call). */
  const MatX& lastTransition() const { return m_piStep; }

  /** The mixing weights mu^{j|i} of the last mix(): column i holds the weights of mode i. */
  const MatX& mixingWeights() const { return m_mixW; }

  /** Fig. 2 step 3: \f$ \mu^i_k \propto \mu^i_{k|k-1} L^i_k \f$ with the log-likelihoods of the
   * joint innovation of all measurements of each mode (eq. 3), normalized in log space, then
   * floored. Call after mix() (uses mu_{k|k-1}). Non-finite log-likelihoods count as -inf; if every
   * one is -inf the probabilities stay at mu_{k|k-1}. */
  void updateProbabilities(const VecX& logLikelihoods);

  /** Fig. 2 step 4 and eqs. (10)-(11): the moment-matched combination of the modes with weights w
   * (mu_k for the fused posterior, mu_{k|k-1} for the fused prediction of the search regions).
   * \param P optional full covariance (O(r n^2)); pass nullptr when only the mean is needed. */
  void combine(const VecX& w, VecX& x, MatX* P, math::CThreadPool* pool = nullptr) const;
  /** Only the diagonal block [off, off+len) of the combined covariance (cheap: O(r len^2)). */
  MatX combinedBlock(const VecX& w, const VecX& xComb, int off, int len) const;
  /** Only the columns [off, off+len) of the combined covariance (O(r n len)). */
  MatX combinedColumns(const VecX& w, const VecX& xComb, int off, int len) const;

 private:
  MatX m_pi;
  MatX m_piStep;  ///< the Markov matrix of the last mix() (pi for one step)
  VecX m_mu, m_muPred;
  MatX m_mixW;
  double m_floor;
  std::vector<TGaussian> m_modes;
  /** m_alias[i] >= 0: mode i's covariance (and mean) is mode m_alias[i]'s (never itself aliased);
   * m_modes[i].P is then stale storage, reused as mode i's output by the next mix(). */
  std::vector<int> m_alias;
  int root(int i) const { return m_alias[i] >= 0 ? m_alias[i] : i; }
  // The steps of mix() (CIMMEstimator.cpp), on the m_mix* buffers below:
  /** Split of the mixing weights into the common terms of each support group and the own terms. */
  void splitMixingWeights(const MatX& pi);
  /** The mixed means and the spreads around xm (m_mixXm, m_mixY, m_mixMuYT(g), m_mixXbar, m_mixYbar). */
  void mixMeans(Eigen::Index n);
  /** Output storage and order (m_mixOrder); true when the covariances are mixed in place. */
  bool prepareMixOutputs(Eigen::Index n);
  /** Column col (rows col..n) of every output covariance; t: the chunk (its m_mixU columns). */
  void mixColumn(Eigen::Index n, Eigen::Index col, int t, int nGroups, bool inplace);
  /** Rows [c0, c1) of the outputs' upper triangles, mirrored from their lower columns. */
  void mirrorChunk(Eigen::Index n, Eigen::Index c0, Eigen::Index c1, bool inplace, const std::vector<char>* lowerOnly);
  /** Gives mode i its own copy of the covariance it shares. */
  void unalias(int i);
  std::atomic<int> m_numAliased{0};  ///< modes with m_alias >= 0 (write access locks only when > 0)
  std::mutex m_aliasMutex;            ///< mode() may be called for different modes from worker threads
  std::vector<MatX> m_scratch;  ///< output buffers of mix() when Delta is not diagonal, swapped with the modes' P
  // Buffers of mix() (kept between calls: no allocation while the dimension stays the same).
  VecX m_mixXm;    ///< xm = sum_j mu^j x^j, the point the mixing is expanded around
  MatX m_mixY;     ///< n x r: y_j = x^j - xm
  MatX m_mixMuYT;  ///< r x n: mu^j y_j^T (column c gives T(:, c) = Y m_mixMuYT(:, c))
  MatX m_mixYbar;  ///< n x r: ybar_i = xbar^i - xm = sum_j mu^{j|i} y_j
  MatX m_mixXbar;  ///< n x r: the mixed means
  MatX m_mixA;     ///< r x r: (pi_ji - beta_i) mu^j / c_i, the weights above the column minimum
  VecX m_mixB;     ///< r: beta_i / c_i, the weight of the common term S_J + T_J of output i's support
  std::vector<int> m_mixGroup;               ///< r: the support group of output i (-1: no common term)
  std::vector<std::vector<char>> m_mixSupp;  ///< per group: which inputs j it sums (pi_ji > 0)
  std::vector<MatX> m_mixMuYTg;              ///< per group: r x n, m_mixMuYT with the rows outside it zero
  MatX m_mixU;     ///< n x (chunks x groups): one column of each group's S_J + T_J per column chunk
  std::vector<int> m_mixOrder;  ///< the order outputs are written in (modes sharing a covariance first)
};
}  // namespace immslam::bayes
