/* imm-monoslam — uncertain rigid transforms (composition of SLAM increments). */
#include <immslam/math/quaternion.h>
#include <immslam/shadow/relative_pose.h>

namespace immslam::shadow
{
Mat3 TUncertainPose::rotation() const { return math::quatToRotation(q); }

TUncertainPose TUncertainPose::inverseMean() const
{
  TUncertainPose o;
  o.q = math::quatConjugate(q);
  o.t = -(math::quatToRotation(o.q) * t);
  return o;
}

Vec3 TUncertainPose::transform(const Vec3& p_B) const { return rotation() * p_B + t; }

TUncertainPose composePoses(const TUncertainPose& a, const TUncertainPose& b, Mat6* J_ab_a, Mat6* J_ab_b)
{
  const Mat3 Ra = a.rotation(), Rb = b.rotation();
  TUncertainPose o;
  o.t = a.t + Ra * b.t;
  o.q = math::quatNormalized(math::quatMultiply(a.q, b.q));
  // Chain rule: Ra Exp(da) (tb + dtb) = Ra tb - Ra [tb]x da + Ra dtb;
  //             Ra Exp(da) Rb Exp(db) = Ra Rb Exp(Rb^T da) Exp(db).
  Mat6 Ja = Mat6::Identity(), Jb = Mat6::Identity();
  Ja.block<3, 3>(0, 3) = -Ra * math::skew(b.t);
  Ja.block<3, 3>(3, 3) = Rb.transpose();
  Jb.block<3, 3>(0, 0) = Ra;
  o.cov = Ja * a.cov * Ja.transpose() + Jb * b.cov * Jb.transpose();
  o.cov = (0.5 * (o.cov + o.cov.transpose())).eval();
  if (J_ab_a) *J_ab_a = Ja;
  if (J_ab_b) *J_ab_b = Jb;
  return o;
}

Mat6 perturbationTransport(const TUncertainPose& T0m, const TUncertainPose& T0k)
{
  const Mat3 R0m = T0m.rotation();
  const Mat3 Rmk = R0m.transpose() * T0k.rotation();
  const Vec3 tmk = R0m.transpose() * (T0k.t - T0m.t);
  Mat6 Phi = Mat6::Identity();
  Phi.block<3, 3>(0, 3) = -R0m * math::skew(tmk);
  Phi.block<3, 3>(3, 3) = Rmk.transpose();
  return Phi;
}

Vec6 posePerturbation(const Vec3& tHat, const Vec4& qHat, const Vec3& t, const Vec4& q)
{
  Vec6 d;
  d.head<3>() = t - tHat;
  d.tail<3>() = math::quatToRotationVector(math::quatMultiply(math::quatConjugate(qHat), q));
  return d;
}

TUncertainPose perturbPose(const TUncertainPose& T, const Vec6& delta)
{
  TUncertainPose o = T;
  o.t += delta.head<3>();
  o.q = math::quatNormalized(math::quatMultiply(T.q, math::quatFromRotationVector(delta.tail<3>())));
  return o;
}
}  // namespace immslam::shadow
