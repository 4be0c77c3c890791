/* imm-monoslam — helpers of the shadow filter's interface types. */
#include <immslam/math/quaternion.h>
#include <immslam/shadow/shadow_types.h>

namespace immslam::shadow
{
std::string className(EShadowClass c)
{
  switch (c)
  {
    case EShadowClass::Pending: return "pending";
    case EShadowClass::Static: return "static";
    case EShadowClass::Dynamic: return "dynamic";
  }
  return "unknown";
}

TCameraMotion TCameraMotion::FromPoses(const Vec3& r0, const Vec4& q0, const Vec3& r1, const Vec4& q1)
{
  TCameraMotion m;
  m.r_W_C = r1;
  m.q_W_C = q1;
  const Mat3 R0 = math::quatToRotation(q0);
  m.t = R0.transpose() * (r1 - r0);
  m.dq = math::quatNormalized(math::quatMultiply(math::quatConjugate(q0), q1));
  return m;
}

}  // namespace immslam::shadow
