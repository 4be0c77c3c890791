/* imm-monoslam — the bundle problem (see bundle_problem.h): measurements joined to poses, points
 * triangulated, reprojection error of a trajectory against the measurements of searches.csv. */
#include <immslam/camera/CCameraModel.h>
#include <immslam/refine/bundle_problem.h>
#include <immslam/eval/statistics.h>
#include <immslam/math/quaternion.h>

#include <Eigen/SVD>
#include <algorithm>
#include <numeric>
#include <cmath>
#include <map>
#include <sstream>
#include <stdexcept>

namespace immslam::refine
{
namespace
{
struct TPoseCW
{
  Mat3 R;
  Vec3 t;
};

TPoseCW cameraFromWorld(const core::TStampedPose& p)
{
  const Mat3 R_WC = math::quatToRotation(p.q_W_C);
  return {R_WC.transpose(), -R_WC.transpose() * p.p_W_C};
}

/** Index of the pose whose timestamp is nearest to t within maxDt, or -1. `order` sorts poses by
 * time. */
long nearestPose(const core::TTrajectory& poses, const std::vector<std::size_t>& order, double t, double maxDt)
{
  const auto it = std::lower_bound(order.begin(), order.end(), t,
                                   [&](std::size_t i, double v) { return poses[i].timestamp < v; });
  long best = -1;
  double bestDt = maxDt;
  for (auto j = it == order.begin() ? it : it - 1; j != order.end() && j <= it; ++j)
  {
    const double dt = std::abs(poses[*j].timestamp - t);
    if (dt <= bestDt) best = static_cast<long>(*j), bestDt = dt;
  }
  return best;
}

/** Linear triangulation (DLT on normalized points), then Gauss-Newton on the reprojection error.
 * Returns false if the point cannot be placed in front of its cameras. */
bool triangulatePoint(const std::vector<TPoseCW>& cams, const std::vector<TBundleObservation>& obs,
                      std::size_t first, std::size_t last, double fx, double fy, Vec3& X)
{
  const std::size_t n = last - first;
  Eigen::MatrixXd A(2 * n, 4);
  for (std::size_t k = 0; k < n; ++k)
  {
    const auto& o = obs[first + k];
    Eigen::Matrix<double, 3, 4> P;
    P << cams[o.pose].R, cams[o.pose].t;
    A.row(2 * k) = o.xn.x() * P.row(2) - P.row(0);
    A.row(2 * k + 1) = o.xn.y() * P.row(2) - P.row(1);
  }
  const Eigen::Vector4d Xh = Eigen::JacobiSVD<Eigen::MatrixXd>(A, Eigen::ComputeFullV).matrixV().col(3);
  // Scene size: the spread of the camera centres (a point is "far" at 1e4 times it).
  Vec3 c0 = -cams[obs[first].pose].R.transpose() * cams[obs[first].pose].t;
  double spread = 0;
  for (std::size_t k = first; k < last; ++k)
    spread = std::max(spread, (-cams[obs[k].pose].R.transpose() * cams[obs[k].pose].t - c0).norm());
  const double far = 1e4 * std::max(spread, 1e-6);
  // The ray of the first view, used when the DLT point is at (or beyond) infinity.
  const auto& o0 = obs[first];
  const Vec3 ray_W = cams[o0.pose].R.transpose() * Vec3(o0.xn.x(), o0.xn.y(), 1).normalized();
  if (std::abs(Xh[3]) * far > Xh.head<3>().norm())
    X = Xh.head<3>() / Xh[3];
  else
    X = c0 + far * ray_W;
  if ((cams[o0.pose].R * X + cams[o0.pose].t).z() <= 0) X = c0 + (X - c0).norm() * ray_W;

  double lambda = 1e-6;
  for (int it = 0; it < 20; ++it)
  {
    Mat3 H = Mat3::Zero();
    Vec3 g = Vec3::Zero();
    double cost = 0;
    for (std::size_t k = first; k < last; ++k)
    {
      Vec2 r;
      Mat23 J;
      if (!reprojectionResidual(cams[obs[k].pose].R, cams[obs[k].pose].t, X, obs[k].xn, fx, fy, r, nullptr, &J))
        return false;
      H += J.transpose() * J;
      g -= J.transpose() * r;  // r = z - h: d r / dX = -d h / dX = J, so the step solves H dX = -J^T r
      cost += r.squaredNorm();
    }
    const Vec3 dX = (H + lambda * Mat3(H.diagonal().asDiagonal()) + 1e-12 * Mat3::Identity()).ldlt().solve(g);
    const Vec3 Xn = X + dX;
    double newCost = 0;
    bool ok = true;
    for (std::size_t k = first; k < last && ok; ++k)
    {
      Vec2 r;
      ok = reprojectionResidual(cams[obs[k].pose].R, cams[obs[k].pose].t, Xn, obs[k].xn, fx, fy, r);
      newCost += r.squaredNorm();
    }
    if (ok && newCost <= cost)
    {
      X = Xn;
      lambda = std::max(lambda / 10, 1e-9);
      if (cost - newCost <= 1e-12 * (1 + cost)) break;
    }
    else
      lambda *= 10;
    if (lambda > 1e6) break;
  }
  return true;
}

std::vector<TPoseCW> cameras(const TBundleProblem& p)
{
  std::vector<TPoseCW> c;
  c.reserve(p.poses.size());
  for (const auto& pose : p.poses) c.push_back(cameraFromWorld(pose));
  return c;
}

/** Every point triangulated from the fixed poses (observations are grouped by point). */
void triangulatePoints(TBundleProblem& p)
{
  const auto cams = cameras(p);
  std::size_t first = 0;
  while (first < p.obs.size())
  {
    std::size_t last = first;
    while (last < p.obs.size() && p.obs[last].point == p.obs[first].point) ++last;
    Vec3 X = p.points[p.obs[first].point];
    if (triangulatePoint(cams, p.obs, first, last, p.fx, p.fy, X)) p.points[p.obs[first].point] = X;
    first = last;
  }
}
}  // namespace

bool reprojectionResidual(const Mat3& R_CW, const Vec3& t_CW, const Vec3& X_W, const Vec2& xn, double fx,
                          double fy, Vec2& r, Eigen::Matrix<double, 2, 6>* J_pose, Mat23* J_point)
{
  const Vec3 RX = R_CW * X_W;
  const Vec3 q = RX + t_CW;
  if (!(q.z() > 0)) return false;
  const double iz = 1.0 / q.z();
  r = Vec2(fx * (xn.x() - q.x() * iz), fy * (xn.y() - q.y() * iz));
  if (!J_pose && !J_point) return true;
  // d r / d q = -diag(fx, fy) d(q_x/q_z, q_y/q_z)/dq.
  Mat23 Jq;
  Jq << -fx * iz, 0, fx * q.x() * iz * iz, 0, -fy * iz, fy * q.y() * iz * iz;
  // q(dtheta) = exp(dtheta) R X + t: d q / d dtheta = -[R X]x.
  if (J_pose)
  {
    J_pose->leftCols<3>() = -Jq * math::skew(RX);
    J_pose->rightCols<3>() = Jq;
  }
  if (J_point) *J_point = Jq * R_CW;
  return true;
}

TBundleProblem makeBundleProblem(const std::vector<eval::TSearchRow>& rows, const core::TTrajectory& poses,
                                 const camera::CCameraModel& cam, double maxDt, int minViews, int minPerPose)
{
  if (minViews < 2) throw std::invalid_argument("makeBundleProblem: minViews must be >= 2");
  if (minPerPose < 1) throw std::invalid_argument("makeBundleProblem: minPerPose must be >= 1");
  if (!(maxDt >= 0)) throw std::invalid_argument("makeBundleProblem: maxDt must be >= 0");
  std::vector<std::size_t> order(poses.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return poses[a].timestamp < poses[b].timestamp; });

  std::size_t used = 0, joined = 0;
  std::map<std::int64_t, std::vector<TBundleObservation>> byFeature;
  std::map<std::int64_t, std::vector<char>> seenFrom;  // one measurement per pose and feature
  for (const auto& row : rows)
  {
    if (!row.usedInUpdate() || !row.z.allFinite()) continue;
    ++used;
    const long pose = nearestPose(poses, order, row.timestamp, maxDt);
    if (pose < 0) continue;
    auto& seen = seenFrom[row.featureId];
    if (seen.empty()) seen.assign(poses.size(), 0);
    if (seen[static_cast<std::size_t>(pose)]) continue;
    seen[static_cast<std::size_t>(pose)] = 1;
    const math::Bearing b = cam.unproject(row.z);
    const Vec3& d = b.unitVector();
    if (!(d.z() > 0)) continue;
    ++joined;
    byFeature[row.featureId].push_back({static_cast<std::size_t>(pose), 0, Vec2(d.x() / d.z(), d.y() / d.z())});
  }

  // Features measured from minViews poses, and poses measuring minPerPose of those features:
  // dropping a weak pose may leave a feature short of views, so repeat until both hold.
  std::vector<std::size_t> perPose(poses.size(), 0);
  std::vector<char> poseKept(poses.size(), 1);
  for (bool changed = true; changed;)
  {
    changed = false;
    std::fill(perPose.begin(), perPose.end(), 0);
    for (const auto& [id, o] : byFeature)
    {
      const auto n = std::count_if(o.begin(), o.end(), [&](const TBundleObservation& m) { return poseKept[m.pose]; });
      if (n >= minViews)
        for (const auto& m : o) perPose[m.pose] += poseKept[m.pose] ? 1 : 0;
    }
    for (std::size_t i = 0; i < poses.size(); ++i)
      if (poseKept[i] && perPose[i] < static_cast<std::size_t>(minPerPose)) poseKept[i] = 0, changed = true;
  }
  // Kept poses in time order (the first one holds the gauge of a refinement).
  TBundleProblem p;
  p.fx = cam.fx();
  p.fy = cam.fy();
  std::vector<std::size_t> newIndex(poses.size(), 0);
  for (const std::size_t i : order)
    if (poseKept[i])
    {
      newIndex[i] = p.poses.size();
      p.poses.push_back(poses[i]);
    }
  for (auto& [id, o] : byFeature)
  {
    std::vector<TBundleObservation> kept;
    for (const auto& m : o)
      if (poseKept[m.pose]) kept.push_back({newIndex[m.pose], p.featureIds.size(), m.xn});
    if (static_cast<int>(kept.size()) < minViews) continue;
    p.featureIds.push_back(id);
    p.obs.insert(p.obs.end(), kept.begin(), kept.end());
  }
  if (p.featureIds.empty())
    throw std::runtime_error("no feature has " + std::to_string(minViews) + " measurements joined to poses that measure " +
                             std::to_string(minPerPose) + " such features (" +
                             std::to_string(used) + " matches used in updates, " + std::to_string(joined) +
                             " joined to a pose within " + std::to_string(maxDt) + " s)");
  p.points.assign(p.featureIds.size(), Vec3::Zero());
  triangulatePoints(p);
  return p;
}

TReprojectionStats reprojectionStats(const TBundleProblem& p, double thresholdPx)
{
  const auto cams = cameras(p);
  TReprojectionStats s;
  s.thresholdPx = thresholdPx;
  s.nFeatures = p.points.size();
  s.nObservations = p.obs.size();
  std::vector<char> posed(p.poses.size(), 0);
  std::vector<double> sum(p.points.size(), 0.0);
  std::vector<std::size_t> cnt(p.points.size(), 0);
  double total = 0;
  for (const auto& o : p.obs)
  {
    Vec2 r;
    const double e2 = reprojectionResidual(cams[o.pose].R, cams[o.pose].t, p.points[o.point], o.xn, p.fx, p.fy, r)
                          ? r.squaredNorm()
                          : std::numeric_limits<double>::infinity();
    sum[o.point] += e2;
    ++cnt[o.point];
    total += e2;
    posed[o.pose] = 1;
  }
  s.nPoses = static_cast<std::size_t>(std::count(posed.begin(), posed.end(), 1));
  s.rmsPx = p.obs.empty() ? 0 : std::sqrt(total / static_cast<double>(p.obs.size()));
  for (std::size_t j = 0; j < sum.size(); ++j)
  {
    s.featureRmsPx.push_back(cnt[j] ? std::sqrt(sum[j] / static_cast<double>(cnt[j])) : 0.0);
    if (s.featureRmsPx.back() > thresholdPx) ++s.featuresAbove;
  }
  if (!s.featureRmsPx.empty())
  {
    s.medianFeatureRmsPx = eval::percentile(s.featureRmsPx, 50);
    s.p90FeatureRmsPx = eval::percentile(s.featureRmsPx, 90);
  }
  return s;
}

TReprojectionStats triangulateAll(TBundleProblem& p, double thresholdPx)
{
  triangulatePoints(p);
  return reprojectionStats(p, thresholdPx);
}

std::vector<std::size_t> componentOfEachPose(const TBundleProblem& p, const std::vector<char>& used)
{
  // Union-find over the poses: the used measurements of one point join their poses.
  std::vector<std::size_t> parent(p.poses.size());
  std::iota(parent.begin(), parent.end(), std::size_t{0});
  const auto find = [&](std::size_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  std::vector<std::size_t> firstPoseOfPoint(p.points.size(), p.poses.size());
  for (std::size_t i = 0; i < p.obs.size(); ++i)
  {
    if (!used.empty() && !used[i]) continue;
    const auto& o = p.obs[i];
    std::size_t& f = firstPoseOfPoint[o.point];
    if (f == p.poses.size())
      f = o.pose;
    else
    {
      const std::size_t a = find(f), b = find(o.pose);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);  // the root is the component's first pose
    }
  }
  std::vector<std::size_t> comp(p.poses.size());
  for (std::size_t i = 0; i < p.poses.size(); ++i) comp[i] = find(i);
  return comp;
}

std::vector<std::size_t> firstPoseOfEachComponent(const TBundleProblem& p, const std::vector<char>& used)
{
  const std::vector<std::size_t> comp = componentOfEachPose(p, used);
  std::vector<std::size_t> roots;
  for (std::size_t i = 0; i < comp.size(); ++i)
    if (comp[i] == i) roots.push_back(i);
  return roots;
}

std::string TReprojectionStats::summary() const
{
  std::ostringstream os;
  os.setf(std::ios::fixed);
  os.precision(3);
  os << "features        : " << nFeatures << " (" << nObservations << " measurements from " << nPoses << " poses)\n"
     << "reprojection RMS: " << rmsPx << " px\n"
     << "per feature RMS : median " << medianFeatureRmsPx << " px, 90th percentile " << p90FeatureRmsPx << " px; "
     << featuresAbove << " features above " << thresholdPx << " px\n";
  return os.str();
}
}  // namespace immslam::refine
