/* imm-monoslam — bundle adjustment on Ceres (see bundle_adjust.h). */
#include <immslam/math/quaternion.h>
#include <immslam/refine/bundle_adjust.h>

#include <ceres/ceres.h>
#include <glog/logging.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <set>

namespace immslam::refine
{
namespace
{
/** One measurement's residual, reprojectionResidual() with automatic derivatives: pose blocks are
 * q_CW (Eigen order x, y, z, w) and t_CW, the point block X_W. */
struct TReprojectionCost
{
  Vec2 xn;
  double fx, fy;

  template <typename T>
  bool operator()(const T* q_CW, const T* t_CW, const T* X_W, T* r) const
  {
    const Eigen::Map<const Eigen::Quaternion<T>> q(q_CW);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t(t_CW), X(X_W);
    const Eigen::Matrix<T, 3, 1> p = q * X + t;
    if (!(p.z() > T(0))) return false;  // behind the camera: the step is rejected
    r[0] = T(fx) * (T(xn.x()) - p.x() / p.z());
    r[1] = T(fy) * (T(xn.y()) - p.y() / p.z());
    return true;
  }
};

/** The distance from a fixed centre c0 to a pose's centre -R_CW^T t_CW, held at d by a stiff
 * residual (the scale gauge of a window). */
struct TDistanceCost
{
  Vec3 c0;
  double d, weight;

  template <typename T>
  bool operator()(const T* q_CW, const T* t_CW, T* r) const
  {
    const Eigen::Map<const Eigen::Quaternion<T>> q(q_CW);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t(t_CW);
    const Eigen::Matrix<T, 3, 1> c = -(q.conjugate() * t);
    r[0] = T(weight) * ((c - c0.cast<T>()).norm() - T(d));
    return true;
  }
};

/** A pose as Ceres parameter blocks (camera from world). */
struct TPoseBlocks
{
  double q[4];  // x, y, z, w
  double t[3];
};

TPoseBlocks toBlocks(const core::TStampedPose& p)
{
  const Eigen::Quaterniond q_WC = math::toEigen(p.q_W_C);
  const Eigen::Quaterniond q_CW = q_WC.normalized().conjugate();
  const Vec3 t_CW = -(q_CW * p.p_W_C);
  return {{q_CW.x(), q_CW.y(), q_CW.z(), q_CW.w()}, {t_CW.x(), t_CW.y(), t_CW.z()}};
}

void fromBlocks(const TPoseBlocks& b, core::TStampedPose& p)
{
  const Eigen::Quaterniond q_CW = Eigen::Quaterniond(b.q[3], b.q[0], b.q[1], b.q[2]).normalized();
  const Eigen::Quaterniond q_WC = q_CW.conjugate();
  p.p_W_C = -(q_WC * Vec3(b.t[0], b.t[1], b.t[2]));
  p.q_W_C = math::fromEigen(q_WC);
}

/** The held poses: those asked for, and the first pose of every component holding none of them. */
std::vector<std::size_t> heldPoses(const TBundleProblem& p, const std::vector<char>& used,
                                   const std::vector<std::size_t>& asked)
{
  const std::vector<std::size_t> comp = componentOfEachPose(p, used);
  std::set<std::size_t> held, heldComponents;
  for (const std::size_t i : asked)
    if (i < p.poses.size()) held.insert(i), heldComponents.insert(comp[i]);
  for (std::size_t i = 0; i < comp.size(); ++i)
    if (comp[i] == i && !heldComponents.count(i)) held.insert(i);
  return {held.begin(), held.end()};
}

ceres::Solver::Options solverOptions(std::size_t nPoses, const TBundleOptions& opts)
{
  ceres::Solver::Options so;
  const bool sparse = ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::SUITE_SPARSE);
  // Held points leave no point block to eliminate: the normal equations are block diagonal.
  if (opts.holdPoints)
    so.linear_solver_type = nPoses <= 2 || !sparse ? ceres::DENSE_QR : ceres::SPARSE_NORMAL_CHOLESKY;
  else
    so.linear_solver_type = nPoses <= 60 || !sparse ? ceres::DENSE_SCHUR : ceres::SPARSE_SCHUR;
  so.max_num_iterations = opts.maxIterations;
  so.function_tolerance = 1e-10;
  so.gradient_tolerance = 1e-12;
  so.parameter_tolerance = 1e-10;
  so.num_threads = 1;
  so.logging_type = ceres::SILENT;
  return so;
}

double huberCost(double n, double k) { return n <= k ? n * n : 2 * k * n - k * k; }

/** The reprojection error (pixels) of every used measurement at the current blocks (infinity for
 * the others). */
std::vector<double> currentErrors(const TBundleProblem& p, const std::vector<TPoseBlocks>& poses,
                                  const std::vector<Vec3>& X, const std::vector<char>& used)
{
  std::vector<double> err(p.obs.size(), std::numeric_limits<double>::infinity());
  for (std::size_t i = 0; i < p.obs.size(); ++i)
  {
    if (!used[i]) continue;
    const auto& o = p.obs[i];
    const Mat3 R_CW = Eigen::Quaterniond(poses[o.pose].q[3], poses[o.pose].q[0], poses[o.pose].q[1], poses[o.pose].q[2])
                          .normalized()
                          .toRotationMatrix();
    Vec2 r;
    if (reprojectionResidual(R_CW, Vec3(poses[o.pose].t[0], poses[o.pose].t[1], poses[o.pose].t[2]), X[o.point], o.xn,
                             p.fx, p.fy, r))
      err[i] = r.norm();
  }
  return err;
}

/** TBundleOptions::outlierFactor times the median of the finite errors, at least outlierMinPx. */
double outlierLimit(std::vector<double> err, const TBundleOptions& opts)
{
  err.erase(std::remove_if(err.begin(), err.end(), [](double e) { return !std::isfinite(e); }), err.end());
  if (err.empty()) return std::numeric_limits<double>::infinity();
  std::nth_element(err.begin(), err.begin() + static_cast<std::ptrdiff_t>(err.size() / 2), err.end());
  return std::max(opts.outlierMinPx, opts.outlierFactor * err[err.size() / 2]);
}

/** The measurements the outlier pass removed (a block, no longer used) leave the problem; those
 * never used (their point behind the camera) stay, as without the pass. */
void eraseRemoved(TBundleProblem& p, const std::vector<char>& used, const std::vector<ceres::ResidualBlockId>& blocks)
{
  std::vector<TBundleObservation> kept;
  kept.reserve(p.obs.size());
  for (std::size_t i = 0; i < p.obs.size(); ++i)
    if (used[i] || !blocks[i]) kept.push_back(p.obs[i]);
  p.obs = std::move(kept);
}

/** TBundleOptions::outlierFactor: the measurements far outside the fitted errors leave the same
 * problem (their residual blocks removed, `used` cleared, counted in res.outliers), which is solved
 * again (`summary`: the last solve's). */
void outlierPass(ceres::Problem& problem, const TBundleProblem& p, const std::vector<TPoseBlocks>& poses,
                 const std::vector<Vec3>& X, const std::vector<ceres::ResidualBlockId>& blocks,
                 const TBundleOptions& opts, std::vector<char>& used, TBundleResult& res,
                 ceres::Solver::Summary& summary)
{
  const std::vector<double> err = currentErrors(p, poses, X, used);
  const double limit = outlierLimit(err, opts);
  for (std::size_t i = 0; i < p.obs.size(); ++i)
    if (used[i] && err[i] > limit)
    {
      problem.RemoveResidualBlock(blocks[i]);
      used[i] = 0;
      ++res.outliers;
    }
  if (res.outliers == 0) return;
  TBundleOptions again = opts;
  again.maxIterations = std::min(opts.maxIterations, opts.outlierIterations);
  ceres::Solve(solverOptions(p.poses.size(), again), &problem, &summary);
  res.iterations += static_cast<int>(summary.iterations.size()) - 1;
}
}  // namespace

TBundleResult bundleAdjust(TBundleProblem& p, const TBundleOptions& opts)
{
  TBundleResult res;
  std::vector<TPoseBlocks> poses;
  poses.reserve(p.poses.size());
  for (const auto& pose : p.poses) poses.push_back(toBlocks(pose));
  // A measurement whose point starts behind its camera (a mismatch the triangulation could not
  // place) has no residual: it is left out of the whole adjustment.
  std::vector<char> used(p.obs.size(), 1);
  double cost0 = 0;
  for (std::size_t i = 0; i < p.obs.size(); ++i)
  {
    const auto& o = p.obs[i];
    Vec2 r;
    const Mat3 R_CW = Eigen::Quaterniond(poses[o.pose].q[3], poses[o.pose].q[0], poses[o.pose].q[1], poses[o.pose].q[2])
                          .toRotationMatrix();
    const Vec3 t_CW(poses[o.pose].t[0], poses[o.pose].t[1], poses[o.pose].t[2]);
    used[i] = reprojectionResidual(R_CW, t_CW, p.points[o.point], o.xn, p.fx, p.fy, r) ? 1 : 0;
    if (used[i]) cost0 += huberCost(r.norm(), opts.huberPx);
  }
  res.unused = static_cast<std::size_t>(std::count(used.begin(), used.end(), 0));
  const std::size_t nUsed = p.obs.size() - res.unused;
  res.initialCost = res.finalCost = nUsed ? cost0 / static_cast<double>(nUsed) : 0;
  res.components = firstPoseOfEachComponent(p, used).size();
  if (nUsed == 0) return res;

  ceres::Problem::Options po;
  po.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(po);
  ceres::EigenQuaternionManifold quaternion;
  ceres::HuberLoss huber(opts.huberPx);  // rho(s) = s or 2 k sqrt(s) - k^2: the cost above
  std::vector<Vec3> X = p.points;
  std::vector<ceres::ResidualBlockId> blocks(p.obs.size(), nullptr);
  for (std::size_t i = 0; i < p.obs.size(); ++i)
  {
    if (!used[i]) continue;
    const auto& o = p.obs[i];
    auto* cost = new ceres::AutoDiffCostFunction<TReprojectionCost, 2, 4, 3, 3>(new TReprojectionCost{o.xn, p.fx, p.fy});
    blocks[i] = problem.AddResidualBlock(cost, &huber, poses[o.pose].q, poses[o.pose].t, X[o.point].data());
  }
  for (auto& b : poses)
    if (problem.HasParameterBlock(b.q)) problem.SetManifold(b.q, &quaternion);
  if (opts.holdPoints)
    for (auto& x : X)
      if (problem.HasParameterBlock(x.data())) problem.SetParameterBlockConstant(x.data());
  for (const std::size_t k : opts.holdPoints ? opts.heldPoses : heldPoses(p, used, opts.heldPoses))
    if (problem.HasParameterBlock(poses[k].q))
    {
      problem.SetParameterBlockConstant(poses[k].q);
      problem.SetParameterBlockConstant(poses[k].t);
    }

  if (opts.scalePoses.size() == 2 && problem.HasParameterBlock(poses[opts.scalePoses[1]].q))
  {
    const Vec3 c0 = p.poses[opts.scalePoses[0]].p_W_C;
    const double d = (p.poses[opts.scalePoses[1]].p_W_C - c0).norm();
    if (d > 0)
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<TDistanceCost, 1, 4, 3>(
                                   new TDistanceCost{c0, d, 1e3 * p.fx / d}),
                               nullptr, poses[opts.scalePoses[1]].q, poses[opts.scalePoses[1]].t);
  }
  ceres::Solver::Summary summary;
  ceres::Solve(solverOptions(p.poses.size(), opts), &problem, &summary);
  res.iterations = static_cast<int>(summary.iterations.size()) - 1;
  if (opts.outlierFactor > 0) outlierPass(problem, p, poses, X, blocks, opts, used, res, summary);

  res.converged = summary.termination_type == ceres::CONVERGENCE;
  // Ceres' cost is 1/2 sum rho(|r|^2): twice it per measurement is the cost above.
  res.finalCost = 2 * summary.final_cost / static_cast<double>(std::max<std::size_t>(1, nUsed - res.outliers));
  for (std::size_t i = 0; i < p.poses.size(); ++i) fromBlocks(poses[i], p.poses[i]);
  p.points = X;
  if (res.outliers > 0) eraseRemoved(p, used, blocks);
  return res;
}

void quietSolverLog()
{
  if (!std::getenv("GLOG_minloglevel")) FLAGS_minloglevel = google::GLOG_FATAL;
}
}  // namespace immslam::refine
