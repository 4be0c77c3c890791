/* imm-monoslam — the depth-free static test (depth_free_test.h). */
#include <immslam/math/chi2.h>
#include <immslam/math/quaternion.h>
#include <immslam/shadow/CRayClassifier.h>
#include <immslam/shadow/depth_free_test.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

namespace immslam::shadow
{
namespace
{
constexpr int kGridIntervals = 64;    ///< grid over [0, wMax] before the Gauss-Newton steps
constexpr int kGaussNewtonSteps = 10;
constexpr int kPowerDirections = 16;  ///< image directions over a half turn (lambda(d) = lambda(-d))

using Mat4x18 = Eigen::Matrix<double, 4, 18>;  ///< d r / d [uv0, uv_m, uv_k, pose_m, pose_k]
using Mat18 = Eigen::Matrix<double, 18, 18>;

/** Everything the test needs at one inverse distance w. */
struct TAtW
{
  bool ok = false;
  Vec4 r = Vec4::Zero(), g = Vec4::Zero();
  Mat4 S = Mat4::Identity(), Si = Mat4::Identity();
  double T = 0;
};

struct TInputs
{
  const camera::CCameraModel& cam;
  Vec3 m0;
  Mat32 J_m0_uv;
  const TDepthFreeView* views[2];
  Mat3 R[2];
  Mat18 noise;  ///< covariance of [uv0, uv_m, uv_k, pose_m, pose_k]
};

TAtW atW(const TInputs& in, double w)
{
  TAtW a;
  Mat4x18 J = Mat4x18::Zero();
  for (int j = 0; j < 2; ++j)
  {
    const Mat3& R = in.R[j];
    const Vec3 p = R.transpose() * (in.m0 - w * in.views[j]->T_0j.t);
    Vec2 uv;
    Mat23 Jpi;
    if (!in.cam.project(p, uv, &Jpi)) return a;
    a.r.segment<2>(2 * j) = in.views[j]->uv - uv;
    // Chain rule: r_j = uv_j - pi(p_j); dp_j/dw = -R^T t, so dr_j/dw = Jpi R^T t.
    a.g.segment<2>(2 * j) = Jpi * (R.transpose() * in.views[j]->T_0j.t);
    // dp_j = R^T dm0 - w R^T dt + [p_j]x dtheta (R = R_hat Exp(dtheta): R^T q = Exp(-dtheta) R_hat^T q).
    J.block<2, 2>(2 * j, 0) = -Jpi * R.transpose() * in.J_m0_uv;
    J.block<2, 2>(2 * j, 2 + 2 * j) = Mat2::Identity();
    J.block<2, 3>(2 * j, 6 + 6 * j) = w * Jpi * R.transpose();
    J.block<2, 3>(2 * j, 9 + 6 * j) = -Jpi * math::skew(p);
  }
  a.S = J * in.noise * J.transpose();
  a.S = 0.5 * (a.S + a.S.transpose());
  const Eigen::LDLT<Mat4> ldlt(a.S);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0)) return a;
  a.Si = ldlt.solve(Mat4::Identity());
  a.T = a.r.dot(a.Si * a.r);
  a.ok = std::isfinite(a.T);
  return a;
}
}  // namespace

TDepthFreeTest depthFreeTest(const camera::CCameraModel& cam, const Vec2& uv0, const TDepthFreeView& vm,
                             const TDepthFreeView& vk, const Mat6& crossCov_km, double sigmaPx, double alpha,
                             double wMax)
{
  return depthFreeTest(cam, uv0, vm, vk, crossCov_km, sigmaPx, geometry::TSignificance::At(alpha), wMax);
}

TDepthFreeTest depthFreeTest(const camera::CCameraModel& cam, const Vec2& uv0, const TDepthFreeView& vm,
                             const TDepthFreeView& vk, const Mat6& crossCov_km, double sigmaPx,
                             const geometry::TSignificance& level, double wMax)
{
  TDepthFreeTest out;
  out.threshold = level.threshold(4);
  out.tau[0] = vm.time;
  out.tau[1] = vk.time;
  TInputs in{cam, Vec3::Zero(), Mat32::Zero(), {&vm, &vk}, {vm.T_0j.rotation(), vk.T_0j.rotation()}, Mat18::Zero()};
  in.m0 = cam.unproject(uv0, &in.J_m0_uv).unitVector();
  in.noise.topLeftCorner<6, 6>() = sigmaPx * sigmaPx * Mat6::Identity();
  in.noise.block<6, 6>(6, 6) = vm.T_0j.cov;
  in.noise.block<6, 6>(12, 12) = vk.T_0j.cov;
  in.noise.block<6, 6>(12, 6) = crossCov_km;
  in.noise.block<6, 6>(6, 12) = crossCov_km.transpose();
  if (!in.m0.allFinite() || !in.noise.allFinite()) return out;

  TAtW best;
  double wBest = 0;
  for (int i = 0; i <= kGridIntervals; ++i)
  {
    const double w = wMax * i / kGridIntervals;
    const TAtW a = atW(in, w);
    if (a.ok && (!best.ok || a.T < best.T)) best = a, wBest = w;
  }
  if (!best.ok) return out;
  // Gauss-Newton in w from the best grid point: r(w + dw) ~ r + dw g.
  TAtW cur = best;
  double w = wBest;
  for (int it = 0; it < kGaussNewtonSteps; ++it)
  {
    const double h = cur.g.dot(cur.Si * cur.g);
    if (!(h > 0)) break;
    const double wNew = std::clamp(w - cur.g.dot(cur.Si * cur.r) / h, 0.0, wMax);
    if (std::abs(wNew - w) < 1e-9 * (1 + wMax)) break;
    const TAtW a = atW(in, wNew);
    if (!a.ok) break;
    cur = a;
    w = wNew;
    if (a.T < best.T) best = a, wBest = wNew;
  }
  out.evaluated = true;
  out.T = best.T;
  out.w = wBest;
  out.r = best.r;
  out.g = best.g;
  out.S = best.S;
  out.rejected = out.T > out.threshold;
  return out;
}

double depthFreeNoncentrality(const TDepthFreeTest& t, const Vec4& d, double wMax)
{
  const Mat4 Si = t.S.ldlt().solve(Mat4::Identity());
  const double h = t.g.dot(Si * t.g);
  const double a = h > 0 ? std::clamp(t.g.dot(Si * d) / h, -wMax, wMax) : 0.0;
  const Vec4 e = d - a * t.g;
  return e.dot(Si * e);
}

double depthFreeDetectionProbability(const TDepthFreeTest& t, double speedPx, double alpha, double wMax)
{
  return depthFreeDetectionProbability(t, speedPx, geometry::TSignificance::At(alpha), wMax);
}

double depthFreeDetectionProbability(const TDepthFreeTest& t, double speedPx, const geometry::TSignificance& level,
                                     double wMax)
{
  if (!t.evaluated) return 0;
  const double thr = level.threshold(4);
  double worst = 1;
  for (int i = 0; i < kPowerDirections; ++i)
  {
    const double phi = M_PI * i / kPowerDirections;
    const Vec2 v = speedPx * Vec2(std::cos(phi), std::sin(phi));
    Vec4 d;
    d << t.tau[0] * v, t.tau[1] * v;
    worst = std::min(worst, 1 - noncentralChi2Cdf(thr, 4, depthFreeNoncentrality(t, d, wMax)));
  }
  return worst;
}
}  // namespace immslam::shadow
