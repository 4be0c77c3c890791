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
}  // namespace immslam::motion
