/* imm-monoslam — the shadow filter's per-feature EKF (MonoSLAMBOT eqs. 1-5). */
#include <immslam/bayes/ekf_update.h>
#include <immslam/math/quaternion.h>
#include <immslam/shadow/feature_ekf.h>

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

namespace immslam::shadow
{
TShadowState initialiseShadowState(const camera::CCameraModel& cam, const Vec2& uv, double sigmaPx,
                                   double rho0, double sigmaRho, double sigmaV)
{
  TShadowState s;
  Mat32 J_b_uv;
  const Vec3 m = cam.unproject(uv, &J_b_uv).unitVector();
  s.x << m, rho0, Vec3::Zero();
  s.P.setZero();
  s.P.topLeftCorner<3, 3>() = sigmaPx * sigmaPx * J_b_uv * J_b_uv.transpose();
  s.P(kW, kW) = sigmaRho * sigmaRho;
  // u = w v with w, v independent: E[u] = 0, Cov(u) = E[w^2] sigmaV^2 I, Cov(u, w) = 0.
  s.P.block<3, 3>(kVel, kVel) = (rho0 * rho0 + sigmaRho * sigmaRho) * sigmaV * sigmaV * Mat3::Identity();
  return s;
}

Vec7 shadowTransition(const Vec7& x, double dt, const Vec3& t, const Vec4& dq, Mat7* J_x, Mat76* J_inc,
                      Mat73* J_V)
{
  const Mat3 Rt = math::quatToRotation(dq).transpose();
  const Vec3 hx = x.head<3>();
  const double w = x[kW];
  const Vec3 u = x.segment<3>(kVel);
  Vec7 out;
  out.head<3>() = Rt * (hx + u * dt - w * t);
  out[kW] = w;
  out.segment<3>(kVel) = Rt * u;
  if (J_x)
  {
    J_x->setZero();
    J_x->block<3, 3>(0, 0) = Rt;
    J_x->block<3, 1>(0, kW) = -Rt * t;
    J_x->block<3, 3>(0, kVel) = dt * Rt;
    (*J_x)(kW, kW) = 1;
    J_x->block<3, 3>(kVel, kVel) = Rt;
  }
  if (J_inc)
  {
    // Chain rule: Exp(dtheta)^T a = a + [a]x dtheta for a = R^T (...).
    J_inc->setZero();
    J_inc->block<3, 3>(0, 0) = -w * Rt;
    J_inc->block<3, 3>(0, 3) = math::skew(out.head<3>());
    J_inc->block<3, 3>(kVel, 3) = math::skew(out.segment<3>(kVel));
  }
  if (J_V)
  {
    // u + w V enters the position times dt and the velocity as is.
    J_V->setZero();
    J_V->block<3, 3>(0, 0) = w * dt * Rt;
    J_V->block<3, 3>(kVel, 0) = w * Rt;
  }
  return out;
}

bool shadowMeasurement(const camera::CCameraModel& cam, const Vec7& x, Vec2& uv, Mat27* J)
{
  Mat23 J_uv_p;
  if (!cam.project(x.head<3>(), uv, J ? &J_uv_p : nullptr)) return false;
  if (J)
  {
    J->setZero();
    J->leftCols<3>() = J_uv_p;
  }
  return uv.allFinite();
}

Vec7 normalizeGauge(const Vec7& x, Mat7* J)
{
  const double n = x.head<3>().norm();
  const Vec7 out = x / n;
  if (J)
  {
    // d(x / |h_xyz|)/dx = I/n - x (h_xyz^T/n, 0, 0, 0, 0) / n^2.
    Eigen::Matrix<double, 1, 7> dn = Eigen::Matrix<double, 1, 7>::Zero();
    dn.head<3>() = x.head<3>().transpose() / n;
    *J = Mat7::Identity() / n - x * dn / (n * n);
  }
  return out;
}

namespace
{
void applyGauge(TShadowState& s)
{
  Mat7 J;
  s.x = normalizeGauge(s.x, &J);
  s.P = J * s.P * J.transpose();
  s.P = (0.5 * (s.P + s.P.transpose())).eval();
}
}  // namespace

void predictShadowState(TShadowState& s, double dt, const Vec3& t, const Vec4& dq, const Mat6& cov_increment,
                        double sigmaAccel)
{
  // The noises enter multiplied by w (w V, w dt): their second moment is (w^2 + P_ww) times theirs
  // (product of independent variables), which matters while the distance is unknown.
  Vec7 xEff = s.x;
  xEff[kW] = std::sqrt(s.x[kW] * s.x[kW] + std::max(s.P(kW, kW), 0.0));
  Mat76 G;
  Mat73 GV;
  shadowTransition(xEff, dt, t, dq, nullptr, &G, &GV);
  Mat7 F;
  s.x = shadowTransition(s.x, dt, t, dq, &F);
  G.block<3, 3>(0, 3) = math::skew(s.x.head<3>());  // the rotation noise acts on the mean
  G.block<3, 3>(kVel, 3) = math::skew(s.x.segment<3>(kVel));
  const double qa = sigmaAccel * sigmaAccel * dt * dt;
  s.P = F * s.P * F.transpose() + G * cov_increment * G.transpose() + qa * GV * GV.transpose();
  applyGauge(s);
}

bool shadowInnovation(const TShadowState& s, const camera::CCameraModel& cam, double sigmaPx, Vec2& h, Mat2& S)
{
  Mat27 H;
  if (!shadowMeasurement(cam, s.x, h, &H)) return false;
  S = H * s.P * H.transpose() + sigmaPx * sigmaPx * Mat2::Identity();
  S = (0.5 * (S + S.transpose())).eval();
  return S.allFinite();
}

bool updateShadowState(TShadowState& s, const camera::CCameraModel& cam, const Vec2& z, double sigmaPx,
                       double* nis)
{
  // The covariance algebra is bayes::ekfUpdate's (S = H P H^T + R, x += K nu, P -= K S K^T);
  // h(x) is the projection of the bearing part only: H has one 2x3 block.
  Vec2 h;
  Mat27 Hx;
  if (!shadowMeasurement(cam, s.x, h, &Hx)) return false;
  bayes::CSparseJacobian H(2, 7);
  H.addBlock(0, 0, Hx.leftCols<3>());
  const VecX nu = z - h;
  VecX x = s.x;
  MatX P = s.P;
  const bayes::TUpdateResult r = bayes::ekfUpdate(x, P, H, nu, VecX::Constant(2, sigmaPx * sigmaPx));
  if (!r.ok) return false;
  if (nis) *nis = r.nis;
  s.x = x;
  s.P = P;
  applyGauge(s);
  return s.x.allFinite() && s.P.allFinite();
}

Vec3 shadowPosition(const TShadowState& s, double wMin, Mat3* cov, Eigen::Matrix<double, 3, 7>* J_p_x)
{
  const double w = std::max(s.x[kW], wMin);
  const Vec3 hx = s.x.head<3>();
  const Vec3 p = hx / w;
  Eigen::Matrix<double, 3, 7> J = Eigen::Matrix<double, 3, 7>::Zero();
  J.leftCols<3>() = Mat3::Identity() / w;
  if (s.x[kW] >= wMin) J.col(kW) = -hx / (w * w);
  if (cov) *cov = J * s.P * J.transpose();
  if (J_p_x) *J_p_x = J;
  return p;
}

Vec3 shadowVelocity(const TShadowState& s, double wMin, Mat3* cov, Eigen::Matrix<double, 3, 7>* J_v_x)
{
  const double w = std::max(s.x[kW], wMin);
  const Vec3 u = s.x.segment<3>(kVel);
  Eigen::Matrix<double, 3, 7> J = Eigen::Matrix<double, 3, 7>::Zero();
  J.block<3, 3>(0, kVel) = Mat3::Identity() / w;
  if (s.x[kW] >= wMin) J.col(kW) = -u / (w * w);
  if (cov) *cov = J * s.P * J.transpose();
  if (J_v_x) *J_v_x = J;
  return u / w;
}
}  // namespace immslam::shadow
