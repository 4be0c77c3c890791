/* imm-monoslam — stationary / rotation / general camera motion models with Jacobians. */
#include <immslam/math/quaternion.h>
#include <immslam/motion/motion_models.h>

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
