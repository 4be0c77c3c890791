/* imm-monoslam — Davison's one-parameter wide-angle camera model. */
#include <immslam/camera/CDavisonCamera.h>

#include "camera_detail.h"

#include <cmath>
#include <stdexcept>

namespace immslam::camera
{
namespace
{
/** Smallest 1 + 2 kd1 r_u^2 accepted by project() (kd1 < 0). */
constexpr double kMinProjectDen = 1e-12;
/** Floor of 1 - 2 kd1 r_d^2 in unproject() (kd1 > 0, pixels at or beyond the limit radius). */
constexpr double kMinUnprojectDen = 1e-6;
}  // namespace

CDavisonCamera::CDavisonCamera(
    int width, int height, double fx, double fy, double cx, double cy, double kd1)
    : CCameraModel(width, height, fx, fy, cx, cy), m_kd1(kd1)
{
  if (!std::isfinite(kd1)) throw std::runtime_error("davison camera: kd1 must be finite");
}

std::vector<double> CDavisonCamera::parameters() const { return {m_fx, m_fy, m_cx, m_cy, m_kd1}; }

bool CDavisonCamera::project(const Vec3& p_C, Vec2& uv, Mat23* J_uv_p) const
{
  if (!detail::inFront(p_C)) return false;
  const double iz = 1.0 / p_C.z();
  // Undistorted pixel offset a = (fx x/z, fy y/z) and its squared radius.
  const Vec2 a(m_fx * p_C.x() * iz, m_fy * p_C.y() * iz);
  const double r2 = a.squaredNorm();
  const double den = 1.0 + 2.0 * m_kd1 * r2;
  if (!(den > kMinProjectDen)) return false;
  const double s = 1.0 / std::sqrt(den);  // r_d / r_u
  uv << m_cx + s * a.x(), m_cy + s * a.y();
  if (J_uv_p)
  {
    // Chain rule: d(s a)/d(a) = s I + a (ds/da)^T with ds/da = -2 kd1 s^3 a;
    // d(a)/d(p) = diag(fx, fy) * d(x/z, y/z)/d(p).
    const Mat2 J_d_a = s * Mat2::Identity() - (2.0 * m_kd1 * s * s * s) * a * a.transpose();
    Mat23 J_a_p;
    J_a_p << m_fx * iz, 0, -a.x() * iz,  //
        0, m_fy * iz, -a.y() * iz;
    *J_uv_p = J_d_a * J_a_p;
  }
  return true;
}

math::Bearing CDavisonCamera::unproject(const Vec2& uv, Mat32* J_b_uv) const
{
  const Vec2 o(uv.x() - m_cx, uv.y() - m_cy);  // distorted pixel offset
  double den = 1.0 - 2.0 * m_kd1 * o.squaredNorm();
  const bool clamped = !(den >= kMinUnprojectDen);
  if (clamped) den = kMinUnprojectDen;
  const double t = 1.0 / std::sqrt(den);  // r_u / r_d
  const Vec2 a = t * o;                   // undistorted pixel offset
  const Vec2 n(a.x() / m_fx, a.y() / m_fy);
  Mat2 J_n_uv = Mat2::Zero();
  if (J_b_uv)
  {
    // d(t o)/d(o) = t I + o (dt/do)^T with dt/do = 2 kd1 t^3 o (t is constant when clamped).
    Mat2 J_a_o = t * Mat2::Identity();
    if (!clamped) J_a_o += (2.0 * m_kd1 * t * t * t) * o * o.transpose();
    J_n_uv.row(0) = J_a_o.row(0) / m_fx;
    J_n_uv.row(1) = J_a_o.row(1) / m_fy;
  }
  return detail::bearingOfNormalized(n, J_n_uv, J_b_uv);
}

CCameraModel::Ptr CDavisonCamera::scaled(double s) const
{
  detail::checkScale(s, modelName());
  // Pixel offsets scale by s, so r_d(s r_u) = s r_d(r_u) needs kd1 / s^2.
  const double kd1 = m_kd1 / (s * s);
  if (!std::isfinite(kd1))
    throw std::runtime_error(modelName() + " camera: scaling by " + detail::exactText(s) + " turns kd1 " +
                             detail::exactText(m_kd1) + " into a non-finite kd1 / s^2");
  return std::make_shared<CDavisonCamera>(detail::scaleSize(m_width, s),
      detail::scaleSize(m_height, s), s * m_fx, s * m_fy, detail::scalePixel(m_cx, s),
      detail::scalePixel(m_cy, s), kd1);
}
}  // namespace immslam::camera
