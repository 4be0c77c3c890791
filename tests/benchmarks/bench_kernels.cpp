/* imm-monoslam — prototype kernels measured against the library's (part of bench_filter).
 *
 * These are NOT used by the library: they quantify the speed-ups recorded in doc/experiments/performance.md
 * on the same data as the library's kernels, and check that they give the same numbers (counter
 * `max_abs_diff` against the library's result). A prototype that was adopted stays here as the
 * record of the comparison.
 *   - mirroring a lower triangle into the upper one: Eigen's transposed assignment (what the
 *     library does after every symmetric update) vs a cache-blocked copy;
 *   - the symmetric rank-m downdate of the EKF update: selfadjoint rankUpdate + mirror vs a plain
 *     GEMM on the full matrix;
 *   - IMM mixing exploiting the structure of the default Markov matrix
 *     pi = alpha I + beta 1 1^T (transition_stay on the diagonal, the rest spread evenly): every
 *     mixed covariance is a combination of ONE common sum and its own mode's covariance,
 *     computed in 2-D tiles that stay in the L2 cache, or column by column over the full matrix.
 *     ADOPTED: CIMMEstimator::mix now uses this algebra, generalised to any Markov matrix (per
 *     column the minimum beta_i of pi, its own terms where pi_ji > beta_i), column chunk by column
 *     chunk (lower part of each column, then the chunk's rows mirrored); BM_ProtoMix keeps the
 *     comparison (the library should be at least as fast as the prototypes);
 *   - the EKF update with the Jacobian blocks' products P H^T and H (P H^T) at compile-time sizes
 *     (2x3, 2x6). */
#include "bench_common.h"

#include <immslam/bayes/CIMMEstimator.h>
#include <immslam/bayes/ekf_update.h>
#include <immslam/math/parallel.h>
#include <immslam/motion/motion_models.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <vector>

namespace
{
namespace bayes = immslam::bayes;
namespace math = immslam::math;
using Eigen::Index;
using immslam::MatX;
using immslam::VecX;

int stateDim(int nFeat) { return immslam::motion::kCamDim + 6 * nFeat; }

MatX covariance(int n, unsigned seed) { return immslam::bench::makeCovariance(n, seed); }
VecX vec(int n, unsigned seed, double scale) { return immslam::bench::makeVector(n, seed, scale); }

/** Copies the strictly lower triangle into the upper one in 32x32 tiles (both sides stay in L1). */
void mirrorLowerBlocked(MatX& P)
{
  const Index n = P.rows();
  constexpr Index b = 32;
  for (Index j0 = 0; j0 < n; j0 += b)
  {
    const Index w = std::min(b, n - j0);
    for (Index c = 0; c < w; ++c)  // diagonal tile
      for (Index r = c + 1; r < w; ++r) P(j0 + c, j0 + r) = P(j0 + r, j0 + c);
    for (Index i0 = j0 + b; i0 < n; i0 += b)
    {
      const Index h = std::min(b, n - i0);
      P.block(j0, i0, w, h) = P.block(i0, j0, h, w).transpose();
    }
  }
}

// Mirror lower -> upper: Eigen's `P.triangularView<StrictlyUpper>() = P.transpose()` (variant 0,
// what ekfUpdate, predictRobocentric and mix do) vs the blocked copy (variant 1).
void BM_ProtoMirror(benchmark::State& st)
{
  const int n = stateDim(static_cast<int>(st.range(0)));
  const int variant = static_cast<int>(st.range(1));
  MatX P = covariance(n, 1);
  for (auto _ : st)
  {
    if (variant == 0)
      P.triangularView<Eigen::StrictlyUpper>() = P.transpose();
    else
      mirrorLowerBlocked(P);
    benchmark::ClobberMemory();
  }
  st.SetLabel(variant == 0 ? "eigen transpose" : "blocked 32x32");
  st.counters["n"] = n;
}
BENCHMARK(BM_ProtoMirror)
    ->ArgNames({"N", "variant"})
    ->ArgsProduct({{50, 100, 150, 200}, {0, 1}})
    ->Unit(benchmark::kMillisecond);

// P -= Z^T Z (Z: m x n), the covariance downdate of ekfUpdate: 0 = selfadjoint rankUpdate + Eigen
// mirror (the library), 1 = rankUpdate + blocked mirror, 2 = full GEMM (twice the flops, no mirror).
void BM_ProtoDowndate(benchmark::State& st)
{
  const int n = stateDim(static_cast<int>(st.range(0)));
  const int m = static_cast<int>(st.range(1));
  const int variant = static_cast<int>(st.range(2));
  const MatX P0 = covariance(n, 2);
  MatX Zt(n, m);
  {
    std::mt19937 rng(3);
    std::normal_distribution<double> g;
    for (Index i = 0; i < Zt.size(); ++i) Zt.data()[i] = 0.01 * g(rng);
  }
  MatX P = P0;
  for (auto _ : st)
  {
    st.PauseTiming();
    P = P0;
    st.ResumeTiming();
    if (variant == 2)
      P.noalias() -= Zt * Zt.transpose();
    else
    {
      P.selfadjointView<Eigen::Lower>().rankUpdate(Zt, -1.0);
      if (variant == 0)
        P.triangularView<Eigen::StrictlyUpper>() = P.transpose();
      else
        mirrorLowerBlocked(P);
    }
    benchmark::ClobberMemory();
  }
  st.SetLabel(variant == 0 ? "rankUpdate+eigen mirror" : variant == 1 ? "rankUpdate+blocked mirror" : "full gemm");
  st.counters["n"] = n;
  st.counters["m"] = m;
}
BENCHMARK(BM_ProtoDowndate)
    ->ArgNames({"N", "m", "variant"})
    ->ArgsProduct({{100, 150, 200}, {60}, {0, 1, 2}})
    ->Unit(benchmark::kMillisecond);

/** The bank of BM_Mix (bench_filter.cpp): 7 modes that differ slightly, the default Markov matrix. */
struct TBank
{
  MatX pi;
  VecX mu;
  std::vector<bayes::TGaussian> modes;
};
TBank makeBank(int n)
{
  TBank b;
  b.pi = MatX::Constant(7, 7, 0.005 / 6);
  b.pi.diagonal().setConstant(0.995);
  b.mu.resize(7);
  b.mu << 0.02, 0.03, 0.05, 0.1, 0.2, 0.3, 0.3;
  const MatX P = covariance(n, 1);
  for (int i = 0; i < 7; ++i) b.modes.push_back({vec(n, 10 + i, 1.0), P * (1.0 + 0.01 * i)});
  return b;
}

/** Mixing for pi = alpha I + beta 1 1^T. With c_i = sum_j pi_ji mu_j, y_j = x_j - xm (xm = sum_j mu_j x_j),
 * ybar_i = mixed mean - xm:
 *   Pbar_i = (beta / c_i) (S + T) + (alpha mu_i / c_i) (P_i + y_i y_i^T) - ybar_i ybar_i^T,
 * S = sum_j mu_j P_j, T = sum_j mu_j y_j y_j^T = Y diag(mu) Y^T (the spread of the means, eq. of Fig. 2
 * step 1 expanded around xm: no cancellation since the y are differences). Lower triangle in 2-D
 * tiles of 64 x 32 (the 7 inputs, the common tile and 7 outputs: ~260 KB, inside L2), then mirrored. */
void mixStructured(const MatX& pi, const VecX& mu, std::vector<bayes::TGaussian>& modes, std::vector<MatX>& outP,
                   math::CThreadPool* pool)
{
  const int r = static_cast<int>(modes.size());
  const Index n = modes[0].x.size();
  const double beta = pi(0, 1), alpha = pi(0, 0) - beta;
  const VecX c = pi.transpose() * mu;
  VecX xm = VecX::Zero(n);
  for (int j = 0; j < r; ++j) xm.noalias() += mu[j] * modes[j].x;
  MatX Y(n, r), Ymu(n, r), Ybar(n, r);
  for (int j = 0; j < r; ++j)
  {
    Y.col(j) = modes[j].x - xm;
    Ymu.col(j) = mu[j] * Y.col(j);
  }
  // Mixed means: xbar_i = sum_j W_ji x_j, W_ji = (alpha delta_ji + beta) mu_j / c_i; sum_j mu_j y_j = 0.
  for (int i = 0; i < r; ++i) Ybar.col(i) = (alpha * mu[i] / c[i]) * Y.col(i);
  outP.resize(r);
  for (int i = 0; i < r; ++i) outP[i].resize(n, n);
  constexpr Index bh = 64, bw = 32;
  const Index nColTiles = (n + bw - 1) / bw;
  auto columnStrip = [&](int t) {
    const Index c0 = t * bw, w = std::min(bw, n - c0);
    MatX U(bh, bw);
    for (Index r0 = c0; r0 < n; r0 += bh)
    {
      const Index h = std::min(bh, n - r0);
      auto u = U.topLeftCorner(h, w);
      u.noalias() = Y.middleRows(r0, h) * Ymu.middleRows(c0, w).transpose();  // T
      for (int j = 0; j < r; ++j) u += mu[j] * modes[j].P.block(r0, c0, h, w);  // + S
      for (int i = 0; i < r; ++i)
      {
        auto o = outP[i].block(r0, c0, h, w);
        const double a = alpha * mu[i] / c[i];
        o = (beta / c[i]) * u + a * modes[i].P.block(r0, c0, h, w);
        o.noalias() += (a * Y.col(i).segment(r0, h)) * Y.col(i).segment(c0, w).transpose();
        o.noalias() -= Ybar.col(i).segment(r0, h) * Ybar.col(i).segment(c0, w).transpose();
      }
    }
  };
  if (pool)
    pool->parallelFor(0, static_cast<int>(nColTiles), columnStrip);
  else
    for (int t = 0; t < nColTiles; ++t) columnStrip(t);
  for (int i = 0; i < r; ++i)
  {
    mirrorLowerBlocked(outP[i]);
    modes[i].x = xm + Ybar.col(i);
  }
}

/** The same algebra as mixStructured, computed column by column over the FULL matrix (both
 * triangles: twice the flops of the lower triangle, but every access sequential and no mirror pass).
 * Columns are dealt to the threads in chunks of 16. */
void mixStructuredColumns(const MatX& pi, const VecX& mu, std::vector<bayes::TGaussian>& modes,
                          std::vector<MatX>& outP, math::CThreadPool* pool)
{
  const int r = static_cast<int>(modes.size());
  const Index n = modes[0].x.size();
  const double beta = pi(0, 1), alpha = pi(0, 0) - beta;
  const VecX c = pi.transpose() * mu;
  VecX xm = VecX::Zero(n);
  for (int j = 0; j < r; ++j) xm.noalias() += mu[j] * modes[j].x;
  MatX Y(n, r), YmuT(r, n), Ybar(n, r);
  for (int j = 0; j < r; ++j)
  {
    Y.col(j) = modes[j].x - xm;
    YmuT.row(j) = mu[j] * Y.col(j).transpose();
  }
  for (int i = 0; i < r; ++i) Ybar.col(i) = (alpha * mu[i] / c[i]) * Y.col(i);
  outP.resize(r);
  for (int i = 0; i < r; ++i) outP[i].resize(n, n);
  constexpr Index chunk = 16;
  const Index nChunks = (n + chunk - 1) / chunk;
  MatX U(n, nChunks);  // one column buffer per job (allocated once)
  auto job = [&](int t) {
    auto u = U.col(t);
    for (Index col = t * chunk; col < std::min(n, (t + 1) * chunk); ++col)
    {
      u.noalias() = Y * YmuT.col(col);  // T(:, col)
      for (int j = 0; j < r; ++j) u.noalias() += mu[j] * modes[j].P.col(col);  // + S(:, col)
      for (int i = 0; i < r; ++i)
      {
        const double a = alpha * mu[i] / c[i];
        outP[i].col(col) = (beta / c[i]) * u + a * modes[i].P.col(col) + (a * Y(col, i)) * Y.col(i) -
                           Ybar(col, i) * Ybar.col(i);
      }
    }
  };
  if (pool)
    pool->parallelFor(0, static_cast<int>(nChunks), job);
  else
    for (int t = 0; t < nChunks; ++t) job(t);
  for (int i = 0; i < r; ++i) modes[i].x = xm + Ybar.col(i);
}

// Mixing: 0 = the library's CIMMEstimator::mix (the generalised structured algebra: lower part of
// each column + mirror per chunk of 16 columns), 1 = the structured prototype in 2-D tiles + blocked
// mirror, 2 = the structured prototype column by column (full matrix, no mirror). The prototypes
// only handle pi = alpha I + beta 1 1^T; before the library adopted the algebra, variant 0 was the
// O(r^2 n^2) tiled sum (n = 253: 1.08 ms vs 0.51 ms for variant 2). Variant 2 computes both
// triangles with different rounding (counter max_asym > 0: not exactly symmetric) and skips the
// mirror. Measured after the adoption (shared 2-core machine, best of 5): at n <= 253 the library
// is 10-20 % faster than variant 2 (half the arithmetic); at n = 613 they are within the noise
// (+-10 %): there the mirror's scattered writes cost about what variant 2's upper triangle does.
void BM_ProtoMix(benchmark::State& st)
{
  const int n = stateDim(static_cast<int>(st.range(0)));
  const int threads = static_cast<int>(st.range(1));
  const int variant = static_cast<int>(st.range(2));
  math::CThreadPool pool(threads);
  const TBank bank = makeBank(n);
  // Reference result of the library (one mix) for the accuracy check.
  bayes::CIMMEstimator ref(bank.pi, bank.mu, 1e-4);
  for (int i = 0; i < 7; ++i) ref.mode(i) = bank.modes[i];
  ref.mix(&pool);
  double maxDiff = 0;
  if (variant == 0)
  {
    bayes::CIMMEstimator imm(bank.pi, bank.mu, 1e-4);
    for (int i = 0; i < 7; ++i) imm.mode(i) = bank.modes[i];
    for (auto _ : st)
    {
      imm.mix(&pool);
      benchmark::ClobberMemory();
    }
  }
  else
  {
    std::vector<bayes::TGaussian> modes = bank.modes;
    std::vector<MatX> outP;
    {
      if (variant == 1)
        mixStructured(bank.pi, bank.mu, modes, outP, &pool);
      else
        mixStructuredColumns(bank.pi, bank.mu, modes, outP, &pool);
      double asym = 0;  // the library's outputs are exactly symmetric; the prototypes' may not be
      for (int i = 0; i < 7; ++i)
      {
        maxDiff = std::max(maxDiff, (outP[i] - ref.mode(i).P).cwiseAbs().maxCoeff());
        maxDiff = std::max(maxDiff, (modes[i].x - ref.mode(i).x).cwiseAbs().maxCoeff());
        asym = std::max(asym, (outP[i] - outP[i].transpose()).cwiseAbs().maxCoeff());
      }
      st.counters["max_asym"] = asym;
    }
    for (auto _ : st)
    {
      if (variant == 1)
        mixStructured(bank.pi, bank.mu, modes, outP, &pool);
      else
        mixStructuredColumns(bank.pi, bank.mu, modes, outP, &pool);
      for (int i = 0; i < 7; ++i) std::swap(modes[i].P, outP[i]);
      benchmark::ClobberMemory();
    }
    st.counters["max_abs_diff"] = maxDiff;
  }
  st.SetLabel(variant == 0 ? "library mix" : variant == 1 ? "structured pi, 2-D tiles" : "structured pi, full columns");
  st.counters["n"] = n;
}
BENCHMARK(BM_ProtoMix)
    ->ArgNames({"N", "threads", "variant"})
    ->ArgsProduct({{20, 40, 100, 150, 200}, {1, 2}, {0, 1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// ---------------------------------------------------------------------------------------------
// ekfUpdate with P H^T and H (P H^T) from fixed-size 2x3 / 2x6 blocks (the rest as the library).
template <int C>
void addPHt(MatX& PHt, const MatX& P, const bayes::CSparseJacobian::TBlock& b)
{
  const Eigen::Map<const Eigen::Matrix<double, 2, C>> J(b.J.data());
  PHt.middleCols<2>(b.row).noalias() += P.middleCols<C>(b.col) * J.transpose();
}
template <int C>
void addHM(MatX& out, const MatX& M, const bayes::CSparseJacobian::TBlock& b)
{
  const Eigen::Map<const Eigen::Matrix<double, 2, C>> J(b.J.data());
  out.middleRows<2>(b.row).noalias() += J * M.middleRows<C>(b.col);
}
bayes::TUpdateResult ekfUpdateFixed(VecX& x, MatX& P, const bayes::CSparseJacobian& H, const VecX& nu, const VecX& Rdiag)
{
  bayes::TUpdateResult res;
  res.dim = static_cast<int>(nu.size());
  MatX PHt = MatX::Zero(P.rows(), H.rows());
  for (const auto& b : H.blocks())
  {
    if (b.J.rows() == 2 && b.J.cols() == 6)
      addPHt<6>(PHt, P, b);
    else if (b.J.rows() == 2 && b.J.cols() == 3)
      addPHt<3>(PHt, P, b);
    else
      PHt.middleCols(b.row, b.J.rows()).noalias() += P.middleCols(b.col, b.J.cols()) * b.J.transpose();
  }
  MatX S = MatX::Zero(H.rows(), H.rows());
  for (const auto& b : H.blocks())
  {
    if (b.J.rows() == 2 && b.J.cols() == 6)
      addHM<6>(S, PHt, b);
    else if (b.J.rows() == 2 && b.J.cols() == 3)
      addHM<3>(S, PHt, b);
    else
      S.middleRows(b.row, b.J.rows()).noalias() += b.J * PHt.middleRows(b.col, b.J.cols());
  }
  S = 0.5 * (S + S.transpose());
  S.diagonal() += Rdiag;
  const Eigen::LLT<MatX> llt(S);
  if (llt.info() != Eigen::Success) return res;
  const auto L = llt.matrixL();
  const VecX z = L.solve(nu);
  MatX Z = PHt.transpose();
  L.solveInPlace(Z);
  res.nis = z.squaredNorm();
  res.logLikelihood =
      -0.5 * (res.nis + 2.0 * llt.matrixLLT().diagonal().array().log().sum() + res.dim * std::log(2 * M_PI));
  x.noalias() += Z.transpose() * z;
  P.selfadjointView<Eigen::Lower>().rankUpdate(Z.transpose(), -1.0);
  P.triangularView<Eigen::StrictlyUpper>() = P.transpose();
  res.ok = true;
  return res;
}

// ekfUpdate: 0 = library, 1 = fixed-size Jacobian blocks. XYZ map (2x3 blocks) or inverse depth
// (2x6), mFeat measured features (m = 2 mFeat).
void BM_ProtoEkfUpdate(benchmark::State& st)
{
  const int nFeat = static_cast<int>(st.range(0));
  const bool xyz = st.range(1) == 1;
  const int mFeat = static_cast<int>(st.range(2));
  const int variant = static_cast<int>(st.range(3));
  const int d = xyz ? 3 : 6;
  const int n = immslam::motion::kCamDim + d * nFeat;
  const MatX P0 = covariance(n, 3);
  const VecX x0 = vec(n, 4, 1.0);
  bayes::CSparseJacobian H(2 * mFeat, n);
  {
    std::mt19937 rng(5);
    std::normal_distribution<double> g;
    for (int a = 0; a < mFeat; ++a)
    {
      MatX J(2, d);
      for (Index i = 0; i < J.size(); ++i) J.data()[i] = 100 * g(rng);
      H.addBlock(2 * a, immslam::motion::kCamDim + d * static_cast<int>((static_cast<long>(a) * nFeat) / mFeat), J);
    }
  }
  const VecX nu = vec(2 * mFeat, 6, 1.0);
  const VecX R = VecX::Constant(2 * mFeat, 1.0);
  {
    MatX Pa = P0, Pb = P0;
    VecX xa = x0, xb = x0;
    const auto ra = bayes::ekfUpdate(xa, Pa, H, nu, R);
    const auto rb = ekfUpdateFixed(xb, Pb, H, nu, R);
    st.counters["max_abs_diff"] = std::max({(Pa - Pb).cwiseAbs().maxCoeff(), (xa - xb).cwiseAbs().maxCoeff(),
                                            std::abs(ra.logLikelihood - rb.logLikelihood)});
  }
  MatX P = P0;
  VecX x = x0;
  for (auto _ : st)
  {
    st.PauseTiming();
    P = P0;
    x = x0;
    st.ResumeTiming();
    const auto res = variant == 0 ? bayes::ekfUpdate(x, P, H, nu, R) : ekfUpdateFixed(x, P, H, nu, R);
    benchmark::DoNotOptimize(res.logLikelihood);
  }
  st.SetLabel(std::string(xyz ? "xyz map, " : "inverse-depth map, ") + (variant == 0 ? "library" : "fixed-size blocks"));
  st.counters["n"] = n;
  st.counters["m"] = 2 * mFeat;
}
BENCHMARK(BM_ProtoEkfUpdate)
    ->ArgNames({"N", "xyz", "mfeat", "variant"})
    ->ArgsProduct({{40, 150}, {1, 0}, {23}, {0, 1}})
    ->Unit(benchmark::kMicrosecond);
}  // namespace
