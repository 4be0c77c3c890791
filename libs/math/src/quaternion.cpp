/* imm-monoslam — unit quaternions with analytic Jacobians. */
#include <immslam/math/quaternion.h>

#include <cmath>

namespace immslam::math
{
Mat3 skew(const Vec3& v)
{
  Mat3 S;
  S << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return S;
}

Mat3 quatToRotation(const Vec4& q) { return toEigen(q).toRotationMatrix(); }

Vec3 quatRotate(const Vec4& q, const Vec3& a, Mat34* J_q, Mat3* J_a)
{
  const double w = q[0];
  const Vec3 v = q.tail<3>();
  // Quadratic form: R(q) a = (w^2 - v.v) a + 2 (v.a) v + 2 w (v x a).
  const Vec3 vxa = v.cross(a);
  const double va = v.dot(a);
  const Vec3 out = (w * w - v.squaredNorm()) * a + 2 * va * v + 2 * w * vxa;
  if (J_q)
  {
    // d/dw = 2 w a + 2 v x a;  d/dv = -2 a v^T + 2 (v.a) I + 2 v a^T - 2 w [a]x.
    J_q->col(0) = 2 * w * a + 2 * vxa;
    J_q->rightCols<3>() = -2 * a * v.transpose() + 2 * va * Mat3::Identity() +
                          2 * v * a.transpose() - 2 * w * skew(a);
  }
  if (J_a)
  {
    *J_a = (w * w - v.squaredNorm()) * Mat3::Identity() + 2 * v * v.transpose() + 2 * w * skew(v);
  }
  return out;
}

Vec4 quatMultiply(const Vec4& q1, const Vec4& q2, Mat4* J_q1, Mat4* J_q2)
{
  const double w1 = q1[0], x1 = q1[1], y1 = q1[2], z1 = q1[3];
  const double w2 = q2[0], x2 = q2[1], y2 = q2[2], z2 = q2[3];
  // q1 (x) q2 = [w1 w2 - v1.v2, w1 v2 + w2 v1 + v1 x v2].
  Mat4 R2;  // right-multiplication matrix: q1 (x) q2 = R2 q1
  R2 << w2, -x2, -y2, -z2, x2, w2, z2, -y2, y2, -z2, w2, x2, z2, y2, -x2, w2;
  const Vec4 out = R2 * q1;
  if (J_q1) *J_q1 = R2;
  if (J_q2)
  {
    // left-multiplication matrix: q1 (x) q2 = L1 q2
    *J_q2 << w1, -x1, -y1, -z1, x1, w1, -z1, y1, y1, z1, w1, -x1, z1, -y1, x1, w1;
  }
  return out;
}

Vec4 quatConjugate(const Vec4& q) { return Vec4(q[0], -q[1], -q[2], -q[3]); }

Vec4 quatFromRotationVector(const Vec3& w, Mat43* J_w)
{
  const double th = w.norm();
  // s(th) = sin(th/2)/th and ds/dth / th, with their series near 0.
  double s, ds_over_th;
  if (th < 1e-4)
  {
    s = 0.5 - th * th / 48.0;
    ds_over_th = -1.0 / 24.0 + th * th / 960.0;
  }
  else
  {
    s = std::sin(th / 2) / th;
    ds_over_th = (std::cos(th / 2) / (2 * th) - std::sin(th / 2) / (th * th)) / th;
  }
  Vec4 q;
  q[0] = std::cos(th / 2);
  q.tail<3>() = s * w;
  if (J_w)
  {
    // d cos(th/2)/dw = -sin(th/2)/2 * w^T/th = -s/2 w^T;  d(s w)/dw = s I + w (ds/dth) w^T/th.
    J_w->row(0) = -0.5 * s * w.transpose();
    J_w->bottomRows<3>() = s * Mat3::Identity() + ds_over_th * w * w.transpose();
  }
  return q;
}

Vec3 quatToRotationVector(const Vec4& qin)
{
  Vec4 q = qin.normalized();
  if (q[0] < 0) q = -q;  // angle in [0, pi]
  const double vn = q.tail<3>().norm();
  if (vn < 1e-12) return 2.0 * q.tail<3>();
  const double angle = 2.0 * std::atan2(vn, q[0]);
  return angle * q.tail<3>() / vn;
}

Vec4 quatNormalized(const Vec4& q, Mat4* J_q)
{
  const double n = q.norm();
  const Vec4 qn = q / n;
  if (J_q) *J_q = (Mat4::Identity() - qn * qn.transpose()) / n;
  return qn;
}

Eigen::Quaterniond toEigen(const Vec4& q) { return Eigen::Quaterniond(q[0], q[1], q[2], q[3]); }

Vec4 fromEigen(const Eigen::Quaterniond& q) { return Vec4(q.w(), q.x(), q.y(), q.z()); }
}  // namespace immslam::math
