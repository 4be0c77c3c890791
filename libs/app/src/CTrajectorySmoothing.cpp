/* imm-monoslam — [output] smooth_trajectory (see CTrajectorySmoothing.h). */
#include "CTrajectorySmoothing.h"

#include <immslam/eval/statistics.h>
#include <immslam/math/quaternion.h>

#include <cmath>
#include <unordered_map>

#include <chrono>
#include <iomanip>
#include <sstream>

namespace immslam::app::detail
{
namespace
{
refine::CKeyframeSmoother::TOptions smootherOptions(bool live)
{
  refine::CKeyframeSmoother::TOptions o;
  o.waitWhenBehind = !live;
  return o;
}
}  // namespace

CTrajectorySmoothing::CTrajectorySmoothing(const camera::CCameraModel& cam, bool live)
    : m_cam(cam), m_smoother(smootherOptions(live), cam.fx(), cam.fy())
{
}

void CTrajectorySmoothing::addFrame(const system::TSystemFrame& fr, const slam::CMonoSlamIMM& slam,
                                    const core::TStampedPose& pose,
                                    const std::vector<system::CHeldBackMatches::TMatch>& heldBack)
{
  refine::TSmootherFrame f;
  f.pose = pose;
  std::unordered_map<std::int64_t, std::size_t> matchOf;
  for (const auto& sr : fr.slam->searches)
  {
    if (sr.status != slam::TSearchRecord::EStatus::LowInnovationInlier &&
        sr.status != slam::TSearchRecord::EStatus::RescuedInlier)
      continue;
    const math::Bearing b = m_cam.unproject(sr.z);
    const Vec3& d = b.unitVector();
    if (!(d.z() > 0)) continue;
    matchOf.emplace(sr.id, f.matches.size());
    f.matches.push_back({sr.id, Vec2(d.x() / d.z(), d.y() / d.z())});
  }
  // The relative sigma of the filter's depth of each matched feature (relative to the camera):
  // sigma_rho / rho for a feature still in inverse depth (the depth's to first order), the
  // position's sigma along the optical axis over the depth for a Euclidean one. Only while the
  // smoother reads them (its start).
  if (m_smoother.wantsDepths())
  {
    const Vec3 axis = math::quatToRotation(pose.q_W_C).col(2);
    for (const auto& feat : slam.features())
    {
      const auto it = matchOf.find(feat.id);
      if (it == matchOf.end()) continue;
      const slam::TFeatureWorldEstimate e = slam.featureWorldEstimate(feat);
      const double z = axis.dot(e.p_W - pose.p_W_C);
      if (!(z > 0)) continue;
      const double rel = e.inverseDepth ? (e.rho > 0 ? std::sqrt(e.cov_tpr(2, 2)) / e.rho : 0.0)
                                        : std::sqrt(axis.dot(e.cov_W * axis)) / z;
      if (!(rel > 0) || !std::isfinite(rel)) continue;
      f.matches[it->second].depthRelSigma = rel;
    }
  }
  // The shadow filter's past matches of the features that turned out static.
  for (const auto& hm : heldBack)
  {
    const math::Bearing b = m_cam.unproject(hm.uv);
    const Vec3& d = b.unitVector();
    if (!(d.z() > 0)) continue;
    refine::TSmootherMatch m;
    m.featureId = hm.id;
    m.xn = Vec2(d.x() / d.z(), d.y() / d.z());
    f.past.emplace_back(hm.frame, m);
  }
  m_smoother.addFrame(std::move(f));
}

void CTrajectorySmoothing::finish(const std::string& path, const std::optional<core::TTrajectory>& gt,
                                  TRunSummary& summary, mrpt::system::COutputLogger& log)
{
  const auto t0 = std::chrono::steady_clock::now();
  m_smoother.finish();
  const double wait = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  m_result = m_smoother.trajectory();
  const core::TTrajectory& traj = m_result;
  core::writeTumTrajectory(traj, path);
  const refine::TSmootherStats st = m_smoother.stats();
  summary.smoothCpuSeconds = st.cpuSeconds;
  if (!st.lagFrames.empty())
  {
    summary.smoothMedianLagFrames = eval::median(st.lagFrames);
    summary.smoothMaxLagFrames = *std::max_element(st.lagFrames.begin(), st.lagFrames.end());
  }
  std::ostringstream m;
  m << std::fixed << std::setprecision(2) << "trajectory_smoothed.txt: " << traj.size() << " poses, " << st.keyframes
    << " keyframes, " << st.optimisations << " window optimisations (" << st.unconverged
    << " stopped before converging, their best step kept); lag median " << summary.smoothMedianLagFrames
    << " frames, max " << summary.smoothMaxLagFrames << "; smoother CPU " << st.cpuSeconds << " s ("
    << 100 * st.cpuSeconds / std::max(summary.wallSeconds, 1e-9) << " % of the run's wall time), " << wait
    << " s waited for it at the end";
  log.logStr(mrpt::system::LVL_INFO, m.str());
  if (gt && traj.size() >= 3)
  {
    try
    {
      summary.ateSmoothed = eval::computeAte(traj, *gt, eval::EAlignment::Sim3, 0.01);
    }
    catch (const std::exception& e)
    {
      log.logStr(mrpt::system::LVL_WARN, std::string("no ATE of the smoothed trajectory: ") + e.what());
    }
  }
}
core::TTrajectory CTrajectorySmoothing::published() const
{
  if (!m_result.empty()) return m_result;
  core::TTrajectory out;
  for (const auto& kf : m_smoother.keyframes())
    if (kf.optimised) out.push_back(kf.smoothedPose);
  return out;
}
}  // namespace immslam::app::detail
