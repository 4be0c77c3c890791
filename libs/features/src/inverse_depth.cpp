/* imm-monoslam — inverse-depth and XYZ point features with analytic Jacobians. */
#include <immslam/features/inverse_depth.h>
#include <immslam/math/quaternion.h>

#include <cmath>
#include <limits>

namespace immslam::features
{
namespace
{
const Vec4 kConjSign(1, -1, -1, -1);  // d(conj(q))/dq = diag(kConjSign)
}

Vec3 inverseDepthToPoint(const Vec6& y, Mat36* J_y)
{
  const double rho = y[5];
  Mat32 J_m;
  const Vec3 m = math::Bearing::DirectionFromAngles(y[3], y[4], J_y ? &J_m : nullptr);
  if (J_y)
  {
    // p = x0 + m/rho: dp/dx0 = I, dp/d(theta,phi) = J_m/rho, dp/drho = -m/rho^2.
    J_y->leftCols<3>().setIdentity();
    J_y->block<3, 2>(0, 3) = J_m / rho;
    J_y->col(5) = -m / (rho * rho);
  }
  return y.head<3>() + m / rho;
}

Vec3 inverseDepthInCamera(const Vec6& y, const Vec3& r, const Vec4& q, Mat36* J_y, Mat3* J_r, Mat34* J_q)
{
  const double rho = y[5];
  Mat32 J_m;
  const Vec3 m = math::Bearing::DirectionFromAngles(y[3], y[4], J_y ? &J_m : nullptr);
  const Vec3 d = y.head<3>() - r;
  const Vec3 a = rho * d + m;  // the ray in W, scaled by rho
  Mat34 J_qc;
  Mat3 R_CW;
  const Vec3 h = math::quatRotate(math::quatConjugate(q), a, J_q ? &J_qc : nullptr, &R_CW);
  // Chain rule: h = R(conj(q)) a(y, r).
  if (J_q) *J_q = J_qc * kConjSign.asDiagonal();
  if (J_r) *J_r = -rho * R_CW;
  if (J_y)
  {
    J_y->leftCols<3>() = rho * R_CW;
    J_y->block<3, 2>(0, 3) = R_CW * J_m;
    J_y->col(5) = R_CW * d;
  }
  return h;
}

Vec3 inverseDepthRay(const Vec6& y, Mat36* J_y)
{
  Mat32 J_m;
  const Vec3 m = math::Bearing::DirectionFromAngles(y[3], y[4], J_y ? &J_m : nullptr);
  if (J_y)
  {
    J_y->leftCols<3>() = y[5] * Mat3::Identity();
    J_y->block<3, 2>(0, 3) = J_m;
    J_y->col(5) = y.head<3>();
  }
  return y[5] * y.head<3>() + m;
}

Vec3 transformPoint(const Vec3& p, const Vec4& dq, const Vec3& t, Mat3* J_p, Mat3* J_t, Mat34* J_dq)
{
  Mat34 J_c;
  Mat3 Rt;
  const Vec3 out = math::quatRotate(math::quatConjugate(dq), p - t, J_dq ? &J_c : nullptr, &Rt);
  // Chain rule: p' = R(conj(dq)) (p - t).
  if (J_p) *J_p = Rt;
  if (J_t) *J_t = -Rt;
  if (J_dq) *J_dq = J_c * kConjSign.asDiagonal();
  return out;
}

Vec6 transformInverseDepth(const Vec6& y, const Vec4& dq, const Vec3& t, Mat6* J_y, Mat63* J_t, Mat64* J_dq)
{
  const bool wantJ = J_y || J_t || J_dq;
  Mat3 J_x0, J_x0t;
  Mat34 J_x0dq;
  const Vec3 x0 = transformPoint(y.head<3>(), dq, t, &J_x0, &J_x0t, wantJ ? &J_x0dq : nullptr);
  Mat32 J_m;
  const Vec3 m = math::Bearing::DirectionFromAngles(y[3], y[4], wantJ ? &J_m : nullptr);
  Mat34 J_mdq;
  const Vec3 m2 = transformPoint(m, dq, Vec3::Zero(), nullptr, nullptr, wantJ ? &J_mdq : nullptr);
  Mat23 J_ang;
  const Vec2 ang = math::Bearing::AzimuthElevation(m2, wantJ ? &J_ang : nullptr);
  Vec6 out;
  out << x0, ang, y[5];
  if (J_y)
  {
    // Chain rule: (theta', phi') = angles(R^T m(theta, phi)); x0' = R^T (x0 - t); rho' = rho.
    J_y->setZero();
    J_y->topLeftCorner<3, 3>() = J_x0;
    J_y->block<2, 2>(3, 3) = J_ang * J_x0 * J_m;  // J_x0 = R^T
    (*J_y)(5, 5) = 1.0;
  }
  if (J_t)
  {
    J_t->setZero();
    J_t->topRows<3>() = J_x0t;
  }
  if (J_dq)
  {
    J_dq->setZero();
    J_dq->topRows<3>() = J_x0dq;
    J_dq->block<2, 4>(3, 0) = J_ang * J_mdq;
  }
  return out;
}

Vec3 xyzInCamera(const Vec3& p_W, const Vec3& r, const Vec4& q, Mat3* J_p, Mat3* J_r, Mat34* J_q)
{
  Mat34 J_qc;
  Mat3 R_CW;
  const Vec3 h = math::quatRotate(math::quatConjugate(q), p_W - r, J_q ? &J_qc : nullptr, &R_CW);
  if (J_q) *J_q = J_qc * kConjSign.asDiagonal();
  if (J_p) *J_p = R_CW;
  if (J_r) *J_r = -R_CW;
  return h;
}

Vec6 initInverseDepth(const Vec3& r, const Vec4& q, const Vec3& b_C, double rho0, Mat63* J_r,
                      Mat64* J_q, Mat63* J_b)
{
  Mat34 J_mq;
  Mat3 R_WC;
  const Vec3 m_W = math::quatRotate(q, b_C, J_q ? &J_mq : nullptr, &R_WC);
  Mat23 J_ang;
  const Vec2 ang = math::Bearing::AzimuthElevation(m_W, &J_ang);
  Vec6 y;
  y << r, ang, rho0;
  // Chain rule: (theta, phi) = angles(R(q) b).
  if (J_r)
  {
    J_r->setZero();
    J_r->topRows<3>().setIdentity();
  }
  if (J_q)
  {
    J_q->setZero();
    J_q->block<2, 4>(3, 0) = J_ang * J_mq;
  }
  if (J_b)
  {
    J_b->setZero();
    J_b->block<2, 3>(3, 0) = J_ang * R_WC;
  }
  return y;
}

double linearityIndex(const Vec6& y, double sigmaRho, const Vec3& r)
{
  const double rho = y[5];
  if (!(rho > 0)) return std::numeric_limits<double>::infinity();
  const Vec3 m = math::Bearing::DirectionFromAngles(y[3], y[4]);
  const Vec3 p = y.head<3>() + m / rho;
  const Vec3 h = p - r;
  const double d1 = h.norm();
  if (!(d1 > 0)) return std::numeric_limits<double>::infinity();
  const double cosAlpha = m.dot(h) / d1;
  return 4.0 * sigmaRho / (rho * rho) * std::abs(cosAlpha) / d1;
}
}  // namespace immslam::features
