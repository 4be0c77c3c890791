/* imm-monoslam — benchmarks of the IMM SLAM filter alone (no images): a measurement-level simulation
 * (known data association, as slam_unittest's simulateRun) drives CMonoSlamIMM::processMeasurements()
 * at map sizes of 20..200 features, single model vs the 7-model bank, 1 and 2 threads; and
 * micro-benchmarks of the pieces: IMM mixing, the sparse EKF update, the camera-centred prediction,
 * the combination of the modes (full, diagonal block, columns).
 *
 * Every feature stays inverse depth (convert_to_xyz off) so the state dimension is exactly
 * n = 13 + 6 N: the worst case of a map of N features (XYZ features would halve their blocks).
 * Times are wall-clock (UseRealTime) so that the 2-thread runs are comparable. */
#include "bench_common.h"

#include <immslam/bayes/CIMMEstimator.h>
#include <immslam/bayes/ekf_update.h>
#include <immslam/camera/CCameraModel.h>
#include <immslam/features/inverse_depth.h>
#include <immslam/math/parallel.h>
#include <immslam/math/quaternion.h>
#include <immslam/motion/motion_models.h>
#include <immslam/tracking/CMonoSlamIMM.h>
#include <immslam/slam/robocentric_prediction.h>

#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace
{
namespace slam = immslam::slam;
namespace bayes = immslam::bayes;
namespace motion = immslam::motion;
namespace math = immslam::math;
using immslam::MatX;
using immslam::Vec2;
using immslam::Vec3;
using immslam::Vec4;
using immslam::VecX;

/** The banks compared: the paper's baseline and the shipped 7-model bank (ini/single.ini, ini/imm7.ini). */
const char* const kSingle = "general:1";
const char* const kImm7 = "stationary rotation:0.1 rotation:0.5 rotation:1 general:0.1 general:0.5 general:1";
const char* bankSpec(int which) { return which == 1 ? kSingle : kImm7; }
const char* bankLabel(int which) { return which == 1 ? "single" : "imm7"; }

constexpr double kPi = 3.14159265358979323846;

/** A static cloud of N points in front of a 320x240 pinhole camera (f = 200 px) that oscillates
 * gently (translation and rotation, period 600 frames), so every point stays in view for ever and
 * the map keeps its size. Each frame measures a sliding window of `perFrame` features with 0.5 px
 * noise (deterministic). */
class CMeasurementScene
{
 public:
  CMeasurementScene(int nPoints, int perFrame, unsigned seed)
      : m_cam(immslam::camera::makeCameraModel("pinhole", 320, 240, {200, 200, 160, 120})), m_perFrame(perFrame)
  {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> U(0, 1);
    for (int j = 0; j < nPoints; ++j)
    {
      const Vec2 uv(40 + 240 * U(rng), 40 + 160 * U(rng));
      const double depth = 2 + 4 * U(rng);
      const Vec3 b = m_cam->unproject(uv).unitVector();
      m_points.push_back(b * (depth / b.z()));
    }
  }
  const immslam::camera::CCameraModel::Ptr& camera() const { return m_cam; }
  int size() const { return static_cast<int>(m_points.size()); }

  /** Inverse distance of point j from the camera centre at frame 0 (its true inverse depth). */
  double trueRho(int j) const { return 1.0 / m_points[j].norm(); }
  /** T_W_C at frame k (W = the camera at frame 0). */
  void pose(long k, Vec3& r, Vec4& q) const
  {
    const double t = 2 * kPi * static_cast<double>(k % 600);
    r = Vec3(0.08 * std::sin(t / 100), 0.03 * std::sin(t / 150), 0.05 * std::sin(t / 200));
    const Vec3 w(0.02 * std::sin(t / 120), 0.03 * std::sin(t / 200), 0.01 * std::sin(t / 300));
    q = math::quatFromRotationVector(w);
  }
  /** Pixels of feature j at frame k, exact. */
  bool pixel(long k, int j, Vec2& uv) const
  {
    Vec3 r;
    Vec4 q;
    pose(k, r, q);
    const Vec3 pc = immslam::features::xyzInCamera(m_points[j], r, q);
    return pc.z() > 0.1 && m_cam->project(pc, uv) && m_cam->isInImage(uv);
  }
  /** The measurements of frame k: (id = point index, noisy pixel). */
  std::vector<std::pair<std::int64_t, Vec2>> measurements(long k) const
  {
    std::mt19937 rng(static_cast<unsigned>(1000003 * k + 17));
    std::normal_distribution<double> g(0, 0.5);
    std::vector<std::pair<std::int64_t, Vec2>> z;
    const int n = size(), m = std::min(m_perFrame, n);
    const int start = static_cast<int>((k * 7) % n);
    for (int a = 0; a < m; ++a)
    {
      const int j = (start + a) % n;
      Vec2 uv;
      if (pixel(k, j, uv)) z.emplace_back(j, uv + Vec2(g(rng), g(rng)));
    }
    return z;
  }

 private:
  immslam::camera::CCameraModel::Ptr m_cam;
  std::vector<Vec3> m_points;
  int m_perFrame;
};

/** A filter that has tracked the scene for `warmup` frames (the map: every point, ids = indices). */
struct TRunningFilter
{
  std::unique_ptr<CMeasurementScene> scene;
  std::unique_ptr<slam::CMonoSlamIMM> filter;
  long frame = 0;

  TRunningFilter(int nPoints, int perFrame, const std::string& models, int threads, int warmup, bool toXyz = false)
  {
    scene = std::make_unique<CMeasurementScene>(nPoints, perFrame, 42);
    slam::CMonoSlamIMM::TOptions o;
    o.num_threads = threads;
    o.convert_to_xyz = toXyz;  // off: n = 13 + 6 N exactly
    o.adaptive_pixel_noise = false;
    o.sigma_pixel = 0.5;
    o.init_linear_velocity_std_px = 1.0;
    o.init_angular_velocity_std_px = 1.0;
    o.max_map_features = 100000;
    slam::TIMMBankOptions b;
    b.models = models;
    filter = std::make_unique<slam::CMonoSlamIMM>(o, b, slam::COnePointRansac::TOptions(), scene->camera());
    filter->processMeasurements(0.0, {});
    std::vector<Vec2> uv0;
    std::vector<std::pair<double, double>> rhoPrior;
    for (int j = 0; j < scene->size(); ++j)
    {
      Vec2 uv;
      scene->pixel(0, j, uv);
      uv0.push_back(uv);
      // XYZ maps: a sharp depth prior (1 %) so that the linearity test converts the features at once
      // (an established map; the scene's small parallax would take thousands of frames).
      if (toXyz) rhoPrior.emplace_back(scene->trueRho(j), 0.01 * scene->trueRho(j));
    }
    filter->addFeaturesAt(cv::Mat(), uv0, rhoPrior);
    for (int k = 0; k < warmup; ++k) step();
  }
  const slam::TFrameReport& step()
  {
    ++frame;
    return filter->processMeasurements(frame / 30.0, scene->measurements(frame));
  }
};

// ---------------------------------------------------------------------------------------------
// The filter: one frame of processMeasurements (mix, predict every mode, update every mode with
// `perFrame` features, model probabilities, fused estimate).
void BM_FilterFrame(benchmark::State& st)
{
  const int nFeat = static_cast<int>(st.range(0));
  const int which = static_cast<int>(st.range(1));
  const int threads = static_cast<int>(st.range(2));
  const int perFrame = 30;
  TRunningFilter run(nFeat, perFrame, bankSpec(which), threads, 30);
  double matched = 0, dormant = 0;
  for (auto _ : st)
  {
    const auto& rep = run.step();
    matched += rep.nMatched;
    dormant += rep.nDormantModes;
  }
  st.SetLabel(bankLabel(which));
  st.counters["dormant"] = benchmark::Counter(dormant, benchmark::Counter::kAvgIterations);
  st.counters["n"] = static_cast<double>(run.filter->fusedMean().size());
  st.counters["models"] = run.filter->models().size();
  st.counters["threads"] = threads;
  st.counters["matched"] = benchmark::Counter(matched, benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_FilterFrame)
    ->ArgNames({"N", "bank", "threads"})
    ->ArgsProduct({{20, 50, 100, 150, 200}, {1, 7}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(1.0);

// The same with an XYZ map (as in the real runs, whose maps are mostly XYZ after the inverse depth ->
// XYZ conversion): n = 13 + 3 N (reported after the warm-up), single thread.
void BM_FilterFrameXYZ(benchmark::State& st)
{
  const int nFeat = static_cast<int>(st.range(0));
  const int which = static_cast<int>(st.range(1));
  TRunningFilter run(nFeat, 30, bankSpec(which), 1, 30, true);
  int nXyz = 0;
  for (const auto& f : run.filter->features()) nXyz += f.kind == slam::EFeatureKind::XYZ ? 1 : 0;
  const double n0 = static_cast<double>(run.filter->fusedMean().size());
  for (auto _ : st) run.step();
  st.SetLabel(bankLabel(which));
  st.counters["n"] = n0;
  st.counters["xyz"] = nXyz;
}
BENCHMARK(BM_FilterFrameXYZ)
    ->ArgNames({"N", "bank"})
    ->ArgsProduct({{20, 50, 100, 150, 200}, {1, 7}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(1.0);

// ---------------------------------------------------------------------------------------------
using immslam::bench::makeCovariance;
using immslam::bench::makeVector;
MatX imm7Transition()
{
  MatX pi = MatX::Constant(7, 7, 0.005 / 6);
  pi.diagonal().setConstant(0.995);
  return pi;
}
/** A 7-mode IMM whose modes differ (as after mode-matched updates). */
std::unique_ptr<bayes::CIMMEstimator> makeBank(int n)
{
  VecX mu(7);
  mu << 0.02, 0.03, 0.05, 0.1, 0.2, 0.3, 0.3;
  auto imm = std::make_unique<bayes::CIMMEstimator>(imm7Transition(), mu, 1e-4);
  const MatX P = makeCovariance(n, 1);
  for (int i = 0; i < 7; ++i)
  {
    imm->mode(i).x = makeVector(n, 10 + i, 1.0);
    imm->mode(i).P = P * (1.0 + 0.01 * i);
  }
  return imm;
}
int stateDim(int nFeat) { return motion::kCamDim + 6 * nFeat; }

// IMM mixing (Fig. 2 step 1) of the 7-model bank.
void BM_Mix(benchmark::State& st)
{
  const int n = stateDim(static_cast<int>(st.range(0)));
  const int threads = static_cast<int>(st.range(1));
  auto imm = makeBank(n);
  math::CThreadPool pool(threads);
  for (auto _ : st)
  {
    imm->mix(&pool);
    benchmark::ClobberMemory();
  }
  st.counters["n"] = n;
  // Nominal traffic, as BM_CopyBank: read 7 P's, write 7 P's (mix reads only the lower triangles:
  // the lower part of each column is computed, then mirrored).
  st.SetBytesProcessed(static_cast<int64_t>(st.iterations()) * 2 * 7 * int64_t(n) * n * 8);
}
BENCHMARK(BM_Mix)
    ->ArgNames({"N", "threads"})
    ->ArgsProduct({{20, 40, 50, 100, 150, 200}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The memory-traffic floor of mixing: copying 7 n x n matrices (read 7, write 7).
void BM_CopyBank(benchmark::State& st)
{
  const int n = stateDim(static_cast<int>(st.range(0)));
  std::vector<MatX> a(7, makeCovariance(n, 2)), b(7, MatX(n, n));
  for (auto _ : st)
  {
    for (int i = 0; i < 7; ++i) b[i] = a[i];
    benchmark::ClobberMemory();
  }
  st.counters["n"] = n;
  st.SetBytesProcessed(static_cast<int64_t>(st.iterations()) * 2 * 7 * int64_t(n) * n * 8);
}
BENCHMARK(BM_CopyBank)->ArgName("N")->Arg(20)->Arg(50)->Arg(100)->Arg(150)->Arg(200)->Unit(benchmark::kMillisecond);

/** A sparse Jacobian of `mFeat` features' 2x6 blocks spread over the map. */
bayes::CSparseJacobian makeJacobian(int nFeat, int mFeat, unsigned seed)
{
  const int n = stateDim(nFeat);
  bayes::CSparseJacobian H(2 * mFeat, n);
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  for (int a = 0; a < mFeat; ++a)
  {
    const int feat = static_cast<int>((static_cast<long>(a) * nFeat) / mFeat);
    MatX J(2, 6);
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 6; ++j) J(i, j) = 100 * g(rng);
    H.addBlock(2 * a, motion::kCamDim + 6 * feat, J);
  }
  return H;
}

// bayes::ekfUpdate of an n x n P with m = 2 x (measured features) scalar measurements.
void BM_EkfUpdate(benchmark::State& st)
{
  const int nFeat = static_cast<int>(st.range(0));
  const int m = static_cast<int>(st.range(1));
  const int n = stateDim(nFeat);
  const MatX P0 = makeCovariance(n, 3);
  const VecX x0 = makeVector(n, 4, 1.0);
  const auto H = makeJacobian(nFeat, m / 2, 5);
  const VecX nu = makeVector(m, 6, 1.0);
  const VecX R = VecX::Constant(m, 1.0);
  MatX P = P0;
  VecX x = x0;
  for (auto _ : st)
  {
    st.PauseTiming();
    P = P0;
    x = x0;
    st.ResumeTiming();
    const auto res = bayes::ekfUpdate(x, P, H, nu, R);
    benchmark::DoNotOptimize(res.logLikelihood);
  }
  st.counters["n"] = n;
  st.counters["m"] = m;
}
BENCHMARK(BM_EkfUpdate)
    ->ArgNames({"N", "m"})
    ->Args({20, 40})
    ->ArgsProduct({{50, 100, 150, 200}, {40, 60, 80}})
    ->Unit(benchmark::kMillisecond);

/** The map of a TGaussian with N inverse-depth features (offsets 13, 19, ...). */
std::vector<slam::TFeature> makeFeatures(int nFeat)
{
  std::vector<slam::TFeature> fs(nFeat);
  for (int k = 0; k < nFeat; ++k)
  {
    fs[k].id = k;
    fs[k].kind = slam::EFeatureKind::InverseDepth;
    fs[k].offset = motion::kCamDim + 6 * k;
  }
  return fs;
}
/** A camera-centred state: world pose, velocities, N inverse-depth features in front of the camera. */
bayes::TGaussian makeSlamState(int nFeat)
{
  bayes::TGaussian g;
  const int n = stateDim(nFeat);
  g.x = makeVector(n, 7, 0.01);
  g.x.segment<4>(motion::kQ) = Vec4(1, 0, 0, 0);
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> U(-0.5, 0.5);
  for (int k = 0; k < nFeat; ++k)
  {
    const int o = motion::kCamDim + 6 * k;
    g.x.segment<3>(o).setZero();
    g.x[o + 3] = U(rng);
    g.x[o + 4] = U(rng);
    g.x[o + 5] = 0.3 + U(rng) * 0.2;
  }
  g.P = makeCovariance(n, 9);
  return g;
}
motion::TMotionModel modelOf(int family)
{
  switch (family)
  {
    case 0: return motion::TMotionModel{motion::EMotionFamily::Stationary, 0, 0.0, "stationary"};
    case 1: return motion::TMotionModel{motion::EMotionFamily::Stationary, 0, 0.1, "stationary, shake 0.1 px"};
    case 2: return motion::TMotionModel{motion::EMotionFamily::Rotation, 0, 1.0, "rotation"};
    default: return motion::TMotionModel{motion::EMotionFamily::General, 1.0, 1.0, "general"};
  }
}

// slam::predictRobocentric of one mode (the per-mode prediction of the bank).
void BM_PredictRobocentric(benchmark::State& st)
{
  const int nFeat = static_cast<int>(st.range(0));
  const int family = static_cast<int>(st.range(1));
  const bayes::TGaussian g0 = makeSlamState(nFeat);
  const auto fs = makeFeatures(nFeat);
  const auto model = modelOf(family);
  const auto inc = motion::motionIncrement(model, Vec3(0.002, 0.001, 0.003), Vec3(0.001, 0.002, 0.0005), 1.0, 200);
  bayes::TGaussian g = g0;
  MatX scratch;
  for (auto _ : st)
  {
    st.PauseTiming();
    g.x = g0.x;
    g.P = g0.P;
    st.ResumeTiming();
    slam::predictRobocentric(g, fs, inc, scratch);
    benchmark::ClobberMemory();
  }
  st.SetLabel(model.name);
  st.counters["n"] = stateDim(nFeat);
}
BENCHMARK(BM_PredictRobocentric)
    ->ArgNames({"N", "model"})
    ->ArgsProduct({{20, 50, 100, 150, 200}, {0, 1, 2, 3}})
    ->Unit(benchmark::kMillisecond);

// CIMMEstimator::combine with the full covariance (O(r n^2); fusedCovariance()).
void BM_CombineFull(benchmark::State& st)
{
  const int n = stateDim(static_cast<int>(st.range(0)));
  const int threads = static_cast<int>(st.range(1));
  auto imm = makeBank(n);
  math::CThreadPool pool(threads);
  VecX x;
  MatX P;
  for (auto _ : st)
  {
    imm->combine(imm->probabilities(), x, &P, &pool);
    benchmark::ClobberMemory();
  }
  st.counters["n"] = n;
}
BENCHMARK(BM_CombineFull)
    ->ArgNames({"N", "threads"})
    ->ArgsProduct({{20, 50, 100, 150, 200}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// CIMMEstimator::combine, mean only (the fused prediction and posterior of every frame).
void BM_CombineMean(benchmark::State& st)
{
  const int n = stateDim(static_cast<int>(st.range(0)));
  auto imm = makeBank(n);
  VecX x;
  for (auto _ : st)
  {
    imm->combine(imm->probabilities(), x, nullptr);
    benchmark::DoNotOptimize(x.data());
  }
  st.counters["n"] = n;
}
BENCHMARK(BM_CombineMean)->ArgName("N")->Arg(20)->Arg(50)->Arg(100)->Arg(150)->Arg(200)->Unit(benchmark::kMicrosecond);

// combinedBlock of one feature's 6x6 block (per searched feature, eq. 14), and of the rho entry
// (per feature and frame: depthKnown and the linearity index).
void BM_CombinedBlock(benchmark::State& st)
{
  const int nFeat = static_cast<int>(st.range(0));
  const int len = static_cast<int>(st.range(1));
  const int n = stateDim(nFeat);
  auto imm = makeBank(n);
  VecX x;
  imm->combine(imm->probabilities(), x, nullptr);
  int k = 0;
  for (auto _ : st)
  {
    const int off = motion::kCamDim + 6 * (k++ % nFeat) + (len == 1 ? 5 : 0);
    MatX B = imm->combinedBlock(imm->probabilities(), x, off, len);
    benchmark::DoNotOptimize(B.data());
  }
  st.counters["n"] = n;
}
BENCHMARK(BM_CombinedBlock)
    ->ArgNames({"N", "len"})
    ->ArgsProduct({{20, 200}, {1, 6}})
    ->Unit(benchmark::kMicrosecond);

// combinedColumns of one feature (n x 6: per 1-point RANSAC hypothesis).
void BM_CombinedColumns(benchmark::State& st)
{
  const int nFeat = static_cast<int>(st.range(0));
  const int n = stateDim(nFeat);
  auto imm = makeBank(n);
  VecX x;
  imm->combine(imm->probabilities(), x, nullptr);
  int k = 0;
  for (auto _ : st)
  {
    MatX C = imm->combinedColumns(imm->probabilities(), x, motion::kCamDim + 6 * (k++ % nFeat), 6);
    benchmark::DoNotOptimize(C.data());
  }
  st.counters["n"] = n;
}
BENCHMARK(BM_CombinedColumns)->ArgName("N")->Arg(20)->Arg(50)->Arg(100)->Arg(150)->Arg(200)->Unit(benchmark::kMicrosecond);

// The fixed cost of one math::CThreadPool::parallelFor over the 7 modes with (almost) no work: the
// hand-off to the worker and back. A frame makes ~5 such calls (mix, predict, search, update, map);
// when the other core is busy the worker is not scheduled at once and the caller waits.
void BM_ParallelForOverhead(benchmark::State& st)
{
  const int threads = static_cast<int>(st.range(0));
  math::CThreadPool pool(threads);
  std::vector<double> out(7, 0.0);
  for (auto _ : st)
  {
    pool.parallelFor(0, 7, [&](int i) { out[i] += 1.0; });
    benchmark::DoNotOptimize(out.data());
  }
}
BENCHMARK(BM_ParallelForOverhead)->ArgName("threads")->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond)->UseRealTime();
}  // namespace

IMMSLAM_BENCHMARK_MAIN();
