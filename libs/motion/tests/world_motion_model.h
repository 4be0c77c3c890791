/* imm-monoslam tests — the world-centred form of the motion models: ground truth for simulations and an
 * independent check of the camera-centred increments (motionIncrement) the filter uses. Test support
 * only: the library predicts in the camera-centred form. */
#pragma once

#include <immslam/math/quaternion.h>
#include <immslam/motion/motion_models.h>

#include <cmath>

namespace immslam::motion
{
/** World-centred form of the same models (a test oracle: it simulates ground truth and checks motionIncrement):
 * camera-state prediction \f$ x_v' = f(x_v, n) \f$ of a model over dt frames, with
 * \param F the transition Jacobian df/dx_v (13x13), \param Q the process noise covariance
 * \f$ G\,\mathrm{diag}(\sigma_a^2 dt^2 I, \sigma_\alpha^2 dt^2 I)\,G^\top \f$ (G = df/d(V, W)), in state
 * units (requires focalPx). The quaternion is normalized after the product (its Jacobian included in F). */
inline Vec13 predictCamera(const TMotionModel& m, const Vec13& xv, double dt, double focalPx, Mat13* F = nullptr,
                           Mat13* Q = nullptr)
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
