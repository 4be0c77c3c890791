/* Test helpers of libs/refine (and of the slam-eval reprojection test): a camera moving past a box
 * of points, its measurements as searches.csv rows, a bent copy of its trajectory, ATE after Sim(3). */
#pragma once

#include <immslam/camera/CCameraModel.h>
#include <immslam/core/TTrajectory.h>
#include <immslam/eval/alignment.h>
#include <immslam/eval/search_nis.h>
#include <immslam/math/quaternion.h>

#include <cmath>
#include <random>
#include <vector>

namespace immslam::refine::test
{
/** A camera moving sideways and forward past a box of points, turning a little. */
struct TScene
{
  core::TTrajectory poses;
  std::vector<Vec3> points;
};

inline TScene makeScene(int nPoses = 60, int nPoints = 50)
{
  TScene s;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ux(-2, 2), uy(-1.5, 1.5), uz(4, 7);
  for (int j = 0; j < nPoints; ++j) s.points.emplace_back(ux(rng), uy(rng), uz(rng));
  for (int i = 0; i < nPoses; ++i)
  {
    core::TStampedPose p;
    p.timestamp = 0.1 * i;
    const double a = 0.05 * i;
    p.p_W_C = Vec3(0.6 * std::sin(a), 0.15 * std::cos(0.7 * a), 0.02 * i);
    p.q_W_C = math::quatFromRotationVector(Vec3(0.03 * std::sin(a), -0.08 * std::sin(a), 0.02 * std::cos(a)));
    s.poses.push_back(p);
  }
  return s;
}

/** The measurements of every point from every pose (distorted pixels of `cam`), with noise. */
inline std::vector<eval::TSearchRow> measure(const TScene& s, const camera::CCameraModel& cam, double noisePx)
{
  std::mt19937 rng(11);
  std::normal_distribution<double> n(0, noisePx);
  std::vector<eval::TSearchRow> rows;
  for (const auto& p : s.poses)
  {
    const Mat3 R_WC = math::quatToRotation(p.q_W_C);
    for (std::size_t j = 0; j < s.points.size(); ++j)
    {
      Vec2 uv;
      if (!cam.project(R_WC.transpose() * (s.points[j] - p.p_W_C), uv) || !cam.isInImage(uv)) continue;
      eval::TSearchRow r;
      r.timestamp = p.timestamp;
      r.featureId = static_cast<std::int64_t>(100 + j);
      r.found = true;
      r.z = uv + Vec2(n(rng), n(rng));
      r.h = r.z;
      r.S = Mat2::Identity();
      r.status = j % 5 == 0 ? eval::ESearchStatus::Rescued : eval::ESearchStatus::Inlier;
      rows.push_back(r);
    }
  }
  return rows;
}

/** The trajectory turned by an angle growing along it (a drift the points cannot all agree with). */
inline core::TTrajectory bend(const core::TTrajectory& t, double maxDeg)
{
  core::TTrajectory out = t;
  for (std::size_t i = 0; i < out.size(); ++i)
  {
    const double f = static_cast<double>(i) / static_cast<double>(out.size() - 1);
    const Vec4 dq = math::quatFromRotationVector(Vec3(0, f * maxDeg * M_PI / 180, 0));
    out[i].q_W_C = math::quatMultiply(dq, out[i].q_W_C);
    out[i].p_W_C += Vec3(0.3 * f, -0.2 * f * f, 0.1 * f);
  }
  return out;
}

inline double rmsAfterSim3(const core::TTrajectory& est, const core::TTrajectory& truth)
{
  const auto a = core::trajectoryPositions(est), b = core::trajectoryPositions(truth);
  const eval::TSim3 S = eval::alignUmeyama(a, b, true);
  double s2 = 0;
  for (std::size_t i = 0; i < a.size(); ++i) s2 += (S.transform(a[i]) - b[i]).squaredNorm();
  return std::sqrt(s2 / static_cast<double>(a.size()));
}

inline camera::CCameraModel::Ptr pinhole() { return camera::parseCalibLine("pinhole 640 480 500 500 319.5 239.5", "test"); }
}  // namespace immslam::refine::test
