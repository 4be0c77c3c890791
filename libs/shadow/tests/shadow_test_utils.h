/* Shared helpers of the shadow filter tests: random numbers, cameras, smooth camera paths. */
#pragma once

#include <immslam/camera/COpenCVCamera.h>
#include <immslam/camera/CPinholeCamera.h>
#include <immslam/math/quaternion.h>
#include <immslam/shadow/CShadowFilter.h>

#include <Eigen/Eigenvalues>

#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <random>
#include <vector>

namespace immslam::shadow::test
{
using Rng = std::mt19937_64;
constexpr double kPi = 3.14159265358979323846;

inline double uniform(Rng& rng, double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); }
inline double gauss(Rng& rng) { return std::normal_distribution<double>(0, 1)(rng); }
inline Vec3 gauss3(Rng& rng) { return Vec3(gauss(rng), gauss(rng), gauss(rng)); }
inline Vec3 randomUnit(Rng& rng) { return gauss3(rng).normalized(); }

/** A sample of N(0, C) (C symmetric PSD). */
template <int N>
Eigen::Matrix<double, N, 1> sampleGaussian(Rng& rng, const Eigen::Matrix<double, N, N>& C)
{
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> es(C);
  Eigen::Matrix<double, N, 1> z;
  for (int i = 0; i < N; ++i) z[i] = gauss(rng) * std::sqrt(std::max(es.eigenvalues()[i], 0.0));
  return es.eigenvectors() * z;
}

/** The measurement-level camera of the brief: f = 200 px, 320x240. */
inline camera::CCameraModel::Ptr simCamera() { return std::make_shared<camera::CPinholeCamera>(320, 240, 200, 200, 160, 120); }

/** A camera with strong radial-tangential distortion (Jacobian tests). */
inline camera::CCameraModel::Ptr distortedCamera()
{
  return std::make_shared<camera::COpenCVCamera>(640, 480, 300, 300, 320, 240, -0.3, 0.1, 0.002, -0.0015, -0.01);
}

/** Orientation whose optical axis (z) points along `forward`, with a roll angle. */
inline Vec4 lookAlong(const Vec3& forward, double roll = 0)
{
  const Vec3 z = forward.normalized();
  Vec3 x = Vec3(0, 1, 0).cross(z);  // y down: x = down x forward... any perpendicular will do
  if (x.norm() < 1e-6) x = Vec3(1, 0, 0).cross(z);
  x.normalize();
  const Vec3 y = z.cross(x);
  Mat3 R;
  R.col(0) = x;
  R.col(1) = y;
  R.col(2) = z;
  const Eigen::Quaterniond q(R * Eigen::AngleAxisd(roll, Vec3::UnitZ()).toRotationMatrix());
  return math::fromEigen(q.normalized());
}

/** A smooth hand-held-like camera path (sums of sinusoids), time in frames. */
struct THandheldPath
{
  Vec3 amp[3], freq[3], phase[3];  ///< position: three harmonics per axis
  Vec3 rotAmp, rotFreq, rotPhase;  ///< orientation wobble (rotation vector components)
  Vec3 drift = Vec3::Zero();       ///< constant velocity (length/frame)
  Vec4 q0 = Vec4(1, 0, 0, 0);

  Vec3 position(double t) const
  {
    Vec3 p = drift * t;
    for (int h = 0; h < 3; ++h)
      for (int a = 0; a < 3; ++a) p[a] += amp[h][a] * std::sin(freq[h][a] * t + phase[h][a]);
    return p;
  }
  Vec4 orientation(double t) const
  {
    Vec3 w;
    for (int a = 0; a < 3; ++a) w[a] = rotAmp[a] * std::sin(rotFreq[a] * t + rotPhase[a]);
    return math::quatNormalized(math::quatMultiply(q0, math::quatFromRotationVector(w)));
  }
};

/** A random hand-held path: mean speed `speed` length/frame over its first `horizon` frames (drift
 * plus harmonics with periods of 1-4 s at 30 Hz), orientation wobble of a few degrees. */
inline THandheldPath randomHandheldPath(Rng& rng, double speed, int horizon = 150)
{
  THandheldPath p;
  // Drift plus harmonics with periods of 1-4 s at 30 Hz.
  p.drift = 0.6 * speed * randomUnit(rng);
  for (int h = 0; h < 3; ++h)
    for (int a = 0; a < 3; ++a)
    {
      p.freq[h][a] = 2 * kPi / uniform(rng, 30, 120);
      p.amp[h][a] = uniform(rng, 0.3, 1.0) * speed / p.freq[h][a] / 3.0;
      p.phase[h][a] = uniform(rng, 0, 2 * kPi);
    }
  for (int a = 0; a < 3; ++a)
  {
    p.rotAmp[a] = uniform(rng, 0.02, 0.08);
    p.rotFreq[a] = 2 * kPi / uniform(rng, 40, 150);
    p.rotPhase[a] = uniform(rng, 0, 2 * kPi);
  }
  // Rescale the translation so that the mean speed is `speed`.
  double len = 0;
  for (int k = 1; k <= horizon; ++k) len += (p.position(k) - p.position(k - 1)).norm();
  const double g = speed * horizon / len;
  p.drift *= g;
  for (int h = 0; h < 3; ++h) p.amp[h] *= g;
  return p;
}

/** Pose of the path at time t, as T_W_C. */
struct TPose
{
  Vec3 r = Vec3::Zero();
  Vec4 q = Vec4(1, 0, 0, 0);
  Mat3 R() const { return math::quatToRotation(q); }
  Vec3 toCamera(const Vec3& p_W) const { return R().transpose() * (p_W - r); }
};

/** The exact camera motion from poses[k-1] to poses[k] (none at k = 0), as frame k at `fps`, with the
 * increment covariance `cov`. */
inline TCameraMotion pathMotion(const std::vector<TPose>& poses, int k, double fps, const Mat6& cov)
{
  const TPose& from = poses[k > 0 ? k - 1 : 0];
  TCameraMotion m = TCameraMotion::FromPoses(from.r, from.q, poses[k].r, poses[k].q);
  m.frame = k;
  m.timestamp = k / fps;
  m.cov_increment = cov;
  return m;
}

/** Starts a feature of `filter` at each point of `pts` that projects into the camera at `pose`; returns
 * each new id's index into the projected points (in the order of `pts`). */
inline std::map<std::int64_t, std::size_t> addSeenPoints(CShadowFilter& filter, const camera::CCameraModel& cam,
                                                         const TPose& pose, const std::vector<Vec3>& pts)
{
  std::vector<Vec2> fresh;
  for (const auto& p : pts)
  {
    Vec2 uv;
    if (cam.project(pose.toCamera(p), uv)) fresh.push_back(uv);
  }
  const auto ids = filter.addFeatures(fresh);
  std::map<std::int64_t, std::size_t> byId;
  for (std::size_t i = 0; i < ids.size(); ++i) byId[ids[i]] = i;
  return byId;
}

inline void report(const char* what, double value) { std::printf("[ shadow   ] %-70s %g\n", what, value); }
}  // namespace immslam::shadow::test
