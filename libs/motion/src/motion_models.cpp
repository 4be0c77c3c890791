/* imm-monoslam — stationary / rotation / general camera motion models with Jacobians. */
#include <immslam/math/quaternion.h>
#include <immslam/motion/motion_models.h>

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace immslam::motion
{
std::string familyName(EMotionFamily f)
{
  switch (f)
  {
    case EMotionFamily::Stationary: return "stationary";
    case EMotionFamily::Rotation: return "rotation";
    case EMotionFamily::General: return "general";
  }
  return "?";
}

EMotionFamily familyFromName(const std::string& name)
{
  if (name == "stationary") return EMotionFamily::Stationary;
  if (name == "rotation") return EMotionFamily::Rotation;
  if (name == "general") return EMotionFamily::General;
  throw std::invalid_argument("unknown motion family '" + name + "' (expected stationary, rotation or general)");
}

std::string TMotionModel::displayName() const
{
  if (!name.empty()) return name;
  std::ostringstream s;
  s << familyName(family);
  if (family == EMotionFamily::Rotation) s << "_" << sigmaAngularPx << "px";
  if (family == EMotionFamily::General)
  {
    s << "_" << sigmaLinearPx << "px";
    if (sigmaAngularPx != sigmaLinearPx) s << "_" << sigmaAngularPx << "px";
  }
  return s.str();
}

TMotionIncrement motionIncrement(const TMotionModel& m, const Vec3& v, const Vec3& w, double dt, double focalPx)
{
  TMotionIncrement inc;
  if (m.family == EMotionFamily::Stationary)
  {
    // A camera at rest on a hand, a tripod or a drone is never perfectly still: an optional
    // zero-mean angular jitter (random walk of the orientation, no velocity, no translation).
    // The camera's shake (TMotionModel::shakePx) is such a jitter too: their variances add.
    inc.identity = true;
    if (m.sigmaAngularPx > 0 || m.shakePx > 0)
    {
      const double var = (m.sigmaAngularPx * m.sigmaAngularPx + m.shakePx * m.shakePx) / (focalPx * focalPx) * dt;
      inc.noiseCov.bottomRightCorner<3, 3>() = Mat3::Identity() * var;
      inc.J_dq_n.block<3, 3>(1, 3) = 0.5 * Mat3::Identity();  // d exp(w)/dw at w = 0
    }
    return inc;
  }
  Mat43 J_exp;
  inc.dq = math::quatFromRotationVector(w * dt, &J_exp);
  inc.J_dq_u.rightCols<3>() = J_exp * dt;
  const double sw = m.sigmaAngularPx / focalPx * dt;
  inc.noiseCov.bottomRightCorner<3, 3>() = Mat3::Identity() * sw * sw;
  inc.uNext.tail<3>() = w;
  inc.J_uNext_u.bottomRightCorner<3, 3>().setIdentity();
  if (m.shakePx > 0) inc.shakeCov = Mat3::Identity() * (m.shakePx * m.shakePx / (focalPx * focalPx) * dt);
  if (m.family == EMotionFamily::General)
  {
    inc.t = v * dt;
    inc.J_t_u.leftCols<3>() = Mat3::Identity() * dt;
    // v' = R(dq)^T v = R(conj(dq)) v; chain rule through dq for dv'/dw.
    Mat34 J_c;
    Mat3 Rt;
    inc.uNext.head<3>() = math::quatRotate(math::quatConjugate(inc.dq), v, &J_c, &Rt);
    inc.J_uNext_u.topLeftCorner<3, 3>() = Rt;
    inc.J_uNext_u.topRightCorner<3, 3>() = J_c * Vec4(1, -1, -1, -1).asDiagonal() * inc.J_dq_u.rightCols<3>();
    const double sa = m.sigmaLinearPx / focalPx * dt;
    inc.noiseCov.topLeftCorner<3, 3>() = Mat3::Identity() * sa * sa;
  }
  return inc;
}

Vec13 predictCamera(const TMotionModel& m, const Vec13& xv, double dt, double focalPx, Mat13* F, Mat13* Q)
{
  Vec13 out = xv;
  if (F) F->setIdentity();
  if (Q) Q->setZero();
  const Vec4 q = xv.segment<4>(kQ);
  const Vec3 v = xv.segment<3>(kV), w = xv.segment<3>(kW);

  if (m.family == EMotionFamily::Stationary)
  {
    out.segment<6>(kV).setZero();
    if (F) F->block<6, 6>(kV, kV).setZero();
    if (Q && m.sigmaAngularPx > 0)
    {
      // Jitter q' = q (x) exp(W): dq'/dW = L(q) * 0.5 [0; I].
      Mat4 L;
      math::quatMultiply(q, Vec4(1, 0, 0, 0), nullptr, &L);
      const Mat43 G = 0.5 * L.rightCols<3>();
      const double sw = m.sigmaAngularPx / focalPx * std::sqrt(dt);
      Q->block<4, 4>(kQ, kQ) = sw * sw * G * G.transpose();
    }
    return out;
  }

  // Rotation part, shared by rotation and general: q' = normalize(q (x) exp((w + W) dt)).
  Mat43 J_dq_wdt;
  const Vec4 dq = math::quatFromRotationVector(w * dt, &J_dq_wdt);
  Mat4 J_qp_q, J_qp_dq, J_norm;
  const Vec4 qp = math::quatMultiply(q, dq, &J_qp_q, &J_qp_dq);
  out.segment<4>(kQ) = math::quatNormalized(qp, &J_norm);
  // Chain rule: dq'/dq = N Rmul(dq); dq'/dw = N Lmul(q) dexp/d(w dt) dt (the same for dq'/dW).
  const Mat43 J_q_w = J_norm * J_qp_dq * J_dq_wdt * dt;
  if (F)
  {
    F->block<4, 4>(kQ, kQ) = J_norm * J_qp_q;
    F->block<4, 3>(kQ, kW) = J_q_w;
  }

  Eigen::Matrix<double, 13, 6> G = Eigen::Matrix<double, 13, 6>::Zero();  // df/d(V, W)
  G.block<4, 3>(kQ, 3) = J_q_w;
  G.block<3, 3>(kW, 3).setIdentity();

  if (m.family == EMotionFamily::Rotation)
  {
    out.segment<3>(kV).setZero();
    if (F) F->block<3, 3>(kV, kV).setZero();
  }
  else
  {
    out.segment<3>(kR) = xv.segment<3>(kR) + v * dt;
    if (F) F->block<3, 3>(kR, kV) = Mat3::Identity() * dt;
    G.block<3, 3>(kR, 0) = Mat3::Identity() * dt;
    G.block<3, 3>(kV, 0).setIdentity();
  }

  if (Q)
  {
    const double sa = m.family == EMotionFamily::General ? m.sigmaLinearPx / focalPx * dt : 0.0;
    const double sw = m.sigmaAngularPx / focalPx * dt;
    Eigen::Matrix<double, 6, 1> var;
    var << sa * sa, sa * sa, sa * sa, sw * sw, sw * sw, sw * sw;
    *Q = G * var.asDiagonal() * G.transpose();
  }
  return out;
}
}  // namespace immslam::motion
