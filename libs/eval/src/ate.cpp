/* imm-monoslam — absolute trajectory error. */
#include <immslam/eval/associate.h>
#include <immslam/eval/ate.h>
#include <immslam/eval/statistics.h>
#include <immslam/math/quaternion.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace immslam::eval
{
namespace
{
Vec4 rotationToQuat(const Mat3& R) { return math::fromEigen(Eigen::Quaterniond(R).normalized()); }

/** Angle of q_a^-1 q_b in degrees, in [0, 180]. */
double angleBetweenDeg(const Vec4& qa, const Vec4& qb)
{
  const Vec4 d = math::quatMultiply(math::quatConjugate(qa), qb);
  return math::quatToRotationVector(d).norm() * 180.0 / M_PI;
}

double ratio(double num, double den)
{
  if (den > 0) return num / den;
  return num > 0 ? std::numeric_limits<double>::infinity() : 0.0;
}

std::string timeRange(const core::TTrajectory& t)
{
  if (t.empty()) return "no poses";
  double lo = t.front().timestamp, hi = lo;
  for (const auto& p : t)
  {
    lo = std::min(lo, p.timestamp);
    hi = std::max(hi, p.timestamp);
  }
  std::ostringstream s;
  s << std::fixed << std::setprecision(6);
  s << t.size() << " poses, t in [" << lo << ", " << hi << "]";
  return s.str();
}
}  // namespace

core::TTrajectory applySim3(const TSim3& S, const core::TTrajectory& traj)
{
  const Vec4 qR = rotationToQuat(S.R);
  core::TTrajectory out = traj;
  for (auto& p : out)
  {
    p.p_W_C = S.transform(p.p_W_C);
    p.q_W_C = math::quatMultiply(qR, p.q_W_C).normalized();
  }
  return out;
}

TSim3 alignTrajectories(const core::TTrajectory& est, const core::TTrajectory& gt,
                        const std::vector<std::pair<size_t, size_t>>& pairs, EAlignment a, int* rank)
{
  if (a == EAlignment::None)
  {
    if (rank) *rank = 3;
    return TSim3{};
  }
  std::vector<Vec3> src, dst;
  src.reserve(pairs.size());
  dst.reserve(pairs.size());
  for (const auto& [i, j] : pairs)
  {
    src.push_back(est.at(i).p_W_C);
    dst.push_back(gt.at(j).p_W_C);
  }
  return alignUmeyama(src, dst, a == EAlignment::Sim3, rank);
}

TAteResult computeAte(const core::TTrajectory& est, const core::TTrajectory& gt, EAlignment a, double maxDt)
{
  const auto pairs = associateByTimestamp(est, gt, maxDt);
  if (pairs.empty())
  {
    std::ostringstream s;
    s << "computeAte: no estimated pose has a ground-truth pose within max dt = " << maxDt
      << " s (estimate: " << timeRange(est) << "; ground truth: " << timeRange(gt) << ")";
    throw std::runtime_error(s.str());
  }
  TAteResult r;
  r.alignment = a;
  r.nPairs = pairs.size();
  const TSim3 S = alignTrajectories(est, gt, pairs, a, &r.alignmentRank);
  r.scale = S.s;
  r.R = S.R;
  r.t = S.t;
  const Vec4 qR = rotationToQuat(S.R);

  std::vector<double> pos, rot;
  pos.reserve(pairs.size());
  rot.reserve(pairs.size());
  for (const auto& [i, j] : pairs)
  {
    TAtePairError e;
    e.iEst = i;
    e.iGt = j;
    e.tEst = est[i].timestamp;
    e.tGt = gt[j].timestamp;
    e.position = (gt[j].p_W_C - S.transform(est[i].p_W_C)).norm();
    e.rotationDeg = angleBetweenDeg(gt[j].q_W_C, math::quatMultiply(qR, est[i].q_W_C));
    pos.push_back(e.position);
    rot.push_back(e.rotationDeg);
    r.errors.push_back(e);
  }
  r.rmse = rms(pos);
  r.mean = mean(pos);
  r.median = median(pos);
  r.max = maxValue(pos);
  r.rotationRmseDeg = rms(rot);

  // Path length and extent over the associated ground-truth poses, in ground-truth time order.
  std::vector<size_t> g;
  g.reserve(pairs.size());
  for (const auto& pr : pairs) g.push_back(pr.second);
  std::sort(g.begin(), g.end(), [&](size_t x, size_t y) {
    return std::make_pair(gt[x].timestamp, x) < std::make_pair(gt[y].timestamp, y);
  });
  Vec3 lo = gt[g.front()].p_W_C, hi = lo;
  for (size_t k = 0; k < g.size(); ++k)
  {
    const Vec3& p = gt[g[k]].p_W_C;
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
    if (k > 0) r.pathLength += (p - gt[g[k - 1]].p_W_C).norm();
  }
  r.extent = (hi - lo).norm();
  r.rmseOverPath = ratio(r.rmse, r.pathLength);
  r.rmseOverExtent = ratio(r.rmse, r.extent);
  return r;
}

std::vector<TAtePairError> ateOverTime(const core::TTrajectory& est, const core::TTrajectory& gt, EAlignment a,
                                       double maxDt)
{
  return computeAte(est, gt, a, maxDt).errors;
}
}  // namespace immslam::eval
