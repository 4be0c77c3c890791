/* imm-monoslam — helpers shared by the benchmark programs (tests/benchmarks): where the shared data
 * and the project live, and the machine's state recorded with every result (the machine is shared:
 * the load average tells how much to trust a figure). */
#pragma once

#include <benchmark/benchmark.h>

#include <Eigen/Core>

#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <thread>

namespace immslam::bench
{
/** ../shared/data (IMMSLAM_SHARED_DATA_DIR), overridable by the environment variable of that name. */
inline std::string sharedDataDir()
{
  if (const char* e = std::getenv("IMMSLAM_SHARED_DATA_DIR"); e && *e) return e;
  return IMMSLAM_SHARED_DATA_DIR;
}

/** The project's source folder (configs in ini/). */
inline std::string sourceDir() { return IMMSLAM_SOURCE_DIR; }

/** True if folder/rgb.txt exists (a dataset folder of ../shared/data/README.md). */
inline bool datasetPresent(const std::string& folder)
{
  return std::filesystem::exists(std::filesystem::path(folder) / "rgb.txt");
}

/** The 1-minute load average (/proc/loadavg), or -1. */
inline double loadAverage1()
{
  std::ifstream f("/proc/loadavg");
  double l = -1;
  f >> l;
  return l;
}

/** Adds the machine's state to the benchmark context (printed in the header, kept in the JSON). */
inline void addMachineContext()
{
  std::ostringstream s;
  s << loadAverage1();
  benchmark::AddCustomContext("loadavg_1min_at_start", s.str());
  benchmark::AddCustomContext("hardware_threads", std::to_string(std::thread::hardware_concurrency()));
#ifdef NDEBUG
  benchmark::AddCustomContext("immslam_build", "NDEBUG (Release-like)");
#else
  benchmark::AddCustomContext("immslam_build", "assertions on (Debug-like: figures not representative)");
#endif
}
/** Test data of the micro-benchmarks: a symmetric positive definite P (n x n) with a correlated
 * structure (sum of a diagonal and a low-rank part, like a SLAM covariance), cheap to build. */
inline Eigen::MatrixXd makeCovariance(int n, unsigned seed)
{
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  Eigen::MatrixXd B(n, 8);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < 8; ++j) B(i, j) = 0.1 * g(rng);
  Eigen::MatrixXd P = B * B.transpose();
  P.diagonal().array() += 0.01;
  return P;
}

/** A vector of n normal samples times scale. */
inline Eigen::VectorXd makeVector(int n, unsigned seed, double scale)
{
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  Eigen::VectorXd x(n);
  for (int i = 0; i < n; ++i) x[i] = scale * g(rng);
  return x;
}
}  // namespace immslam::bench

/** main() of every benchmark program: Google Benchmark's, plus the machine context. */
#define IMMSLAM_BENCHMARK_MAIN()                                          \
  int main(int argc, char** argv)                                         \
  {                                                                       \
    benchmark::Initialize(&argc, argv);                                   \
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;     \
    immslam::bench::addMachineContext();                                  \
    benchmark::RunSpecifiedBenchmarks();                                  \
    benchmark::Shutdown();                                                \
    return 0;                                                             \
  }
