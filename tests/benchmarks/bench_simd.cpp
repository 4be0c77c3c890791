/* imm-monoslam — what wider SIMD would buy: the filter's dense kernels in plain Eigen, compiled twice
 * (tests/benchmarks/CMakeLists.txt): bench_simd_sse2 with the project's flags (x86-64 baseline:
 * SSE2) and bench_simd_avx2 with -mavx2 -mfma -DEIGEN_MAX_ALIGN_BYTES=16 (the setting that keeps
 * Eigen's object layout and alignment ABI-compatible with Debian's MRPT build, cf.
 * ../shared/MRPT_NOTES.md). Compare the two programs' figures. Sizes: the state dimensions of the
 * real runs (n = 133: ~40 XYZ features; 253: 40 inverse-depth features) and of the benchmark maps
 * (463, 913), m = 46 scalar measurements (23 matched features, the real runs' median).
 * Standalone (Eigen only) so that no Eigen template compiled for one instruction set is shared
 * with code compiled for the other. */
#include <benchmark/benchmark.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include <random>
#include <string>
#include <vector>

namespace
{
using MatX = Eigen::MatrixXd;
using VecX = Eigen::VectorXd;
using Eigen::Index;

MatX randomMatrix(Index r, Index c, unsigned seed, double scale)
{
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  MatX A(r, c);
  for (Index i = 0; i < A.size(); ++i) A.data()[i] = scale * g(rng);
  return A;
}
MatX spd(Index n, unsigned seed)
{
  const MatX B = randomMatrix(n, 8, seed, 0.1);
  MatX P = B * B.transpose();
  P.diagonal().array() += 0.01;
  return P;
}

void addContext()
{
#if defined(__AVX2__) && defined(__FMA__)
  benchmark::AddCustomContext("simd", "AVX2+FMA (EIGEN_MAX_ALIGN_BYTES=" + std::to_string(EIGEN_MAX_ALIGN_BYTES) + ")");
#else
  benchmark::AddCustomContext("simd", "SSE2 (x86-64 baseline, the project's flags)");
#endif
  benchmark::AddCustomContext("eigen_simd", Eigen::SimdInstructionSetsInUse());
}

// The EKF covariance downdate P -= Z^T Z (lower triangle) + mirror: ekfUpdate's main cost.
void BM_Downdate(benchmark::State& st)
{
  const Index n = st.range(0), m = st.range(1);
  const MatX P0 = spd(n, 1), Zt = randomMatrix(n, m, 2, 0.01);
  MatX P = P0;
  for (auto _ : st)
  {
    st.PauseTiming();
    P = P0;
    st.ResumeTiming();
    P.selfadjointView<Eigen::Lower>().rankUpdate(Zt, -1.0);
    P.triangularView<Eigen::StrictlyUpper>() = P.transpose();
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_Downdate)->ArgNames({"n", "m"})->ArgsProduct({{133, 253, 463, 913}, {46}})->Unit(benchmark::kMicrosecond);

// The triangular solve Z = L^-1 (P H^T)^T (m x n) of ekfUpdate.
void BM_TriangularSolve(benchmark::State& st)
{
  const Index n = st.range(0), m = st.range(1);
  const MatX S = spd(m, 3) + MatX::Identity(m, m);
  const Eigen::LLT<MatX> llt(S);
  const MatX Z0 = randomMatrix(m, n, 4, 1.0);
  MatX Z = Z0;
  for (auto _ : st)
  {
    Z = Z0;
    llt.matrixL().solveInPlace(Z);
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_TriangularSolve)->ArgNames({"n", "m"})->ArgsProduct({{133, 253, 463, 913}, {46}})->Unit(benchmark::kMicrosecond);

// The mixing inner loop of CIMMEstimator::mix: 7 outputs, each a weighted sum of 7 inputs plus a
// rank-7 spread product, in column strips of 16 (lower triangle), then mirrored.
void BM_MixKernel(benchmark::State& st)
{
  const Index n = st.range(0);
  constexpr int r = 7;
  std::vector<MatX> in, out(r, MatX(n, n));
  std::vector<MatX> D;
  for (int i = 0; i < r; ++i)
  {
    in.push_back(spd(n, 10 + i));
    D.push_back(randomMatrix(n, r, 20 + i, 0.01));
  }
  const MatX W = (randomMatrix(r, r, 30, 1.0).array().abs() / 7.0).matrix();
  constexpr Index bw = 16;
  for (auto _ : st)
  {
    for (Index c0 = 0; c0 < n; c0 += bw)
    {
      const Index w = std::min(bw, n - c0), h = n - c0;
      for (int i = 0; i < r; ++i)
      {
        auto o = out[i].block(c0, c0, h, w);
        o.noalias() = D[i].bottomRows(h) * D[i].middleRows(c0, w).transpose();
        for (int j = 0; j < r; ++j) o += W(j, i) * in[j].block(c0, c0, h, w);
      }
    }
    for (int i = 0; i < r; ++i) out[i].triangularView<Eigen::StrictlyUpper>() = out[i].transpose();
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_MixKernel)->ArgName("n")->Arg(133)->Arg(253)->Arg(463)->Arg(913)->Unit(benchmark::kMicrosecond);

// The camera-centred prediction's block products with compile-time sizes: for every 6-block,
// M_b = D_b P_b + G_b P_u (6 x n), then P'_b = M_b D_b^T + M_u G_b^T (n x 6): one mode, inverse-depth map.
void BM_PredictBlocks(benchmark::State& st)
{
  const Index n = st.range(0);
  const MatX P0 = spd(n, 5);
  MatX P = P0, M(n, n);
  const Eigen::Matrix<double, 6, 6> D = Eigen::Matrix<double, 6, 6>::Identity() + 0.01 * Eigen::Matrix<double, 6, 6>::Random();
  const Eigen::Matrix<double, 6, 6> G = 0.01 * Eigen::Matrix<double, 6, 6>::Random();
  constexpr Index u = 7;
  for (auto _ : st)
  {
    st.PauseTiming();
    P = P0;
    st.ResumeTiming();
    for (Index off = 13; off + 6 <= n; off += 6)
    {
      M.middleRows<6>(off).noalias() = D * P.middleRows<6>(off);
      M.middleRows<6>(off).noalias() += G * P.middleRows<6>(u);
    }
    for (Index off = 13; off + 6 <= n; off += 6)
    {
      const Index h = n - off;
      P.block(off, off, h, 6).noalias() = M.block(off, off, h, 6) * D.transpose();
      P.block(off, off, h, 6).noalias() += M.block(off, u, h, 6) * G.transpose();
    }
    P.triangularView<Eigen::StrictlyUpper>() = P.transpose();
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_PredictBlocks)->ArgName("n")->Arg(133)->Arg(253)->Arg(463)->Arg(913)->Unit(benchmark::kMicrosecond);
}  // namespace

int main(int argc, char** argv)
{
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  addContext();
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
