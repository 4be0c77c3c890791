/* imm-monoslam — the ideal pinhole camera. */
#include <immslam/camera/CPinholeCamera.h>

#include "camera_detail.h"

namespace immslam::camera
{
CPinholeCamera::CPinholeCamera(int width, int height, double fx, double fy, double cx, double cy)
    : CCameraModel(width, height, fx, fy, cx, cy)
{
}

std::vector<double> CPinholeCamera::parameters() const { return {m_fx, m_fy, m_cx, m_cy}; }

bool CPinholeCamera::project(const Vec3& p_C, Vec2& uv, Mat23* J_uv_p) const
{
  if (!detail::inFront(p_C)) return false;
  const double iz = 1.0 / p_C.z();
  const double x = p_C.x() * iz, y = p_C.y() * iz;
  uv.x() = m_fx * x + m_cx;
  uv.y() = m_fy * y + m_cy;
  if (J_uv_p)
  {
    // Chain rule: d(uv)/d(p) = diag(fx, fy) * d(x/z, y/z)/d(p).
    (*J_uv_p) << m_fx * iz, 0, -m_fx * x * iz,  //
        0, m_fy * iz, -m_fy * y * iz;
  }
  return true;
}

math::Bearing CPinholeCamera::unproject(const Vec2& uv, Mat32* J_b_uv) const
{
  const Vec2 n((uv.x() - m_cx) / m_fx, (uv.y() - m_cy) / m_fy);
  Mat2 J_n_uv = Mat2::Zero();
  J_n_uv(0, 0) = 1.0 / m_fx;
  J_n_uv(1, 1) = 1.0 / m_fy;
  return detail::bearingOfNormalized(n, J_n_uv, J_b_uv);
}

CCameraModel::Ptr CPinholeCamera::scaled(double s) const
{
  detail::checkScale(s, modelName());
  return std::make_shared<CPinholeCamera>(detail::scaleSize(m_width, s),
      detail::scaleSize(m_height, s), s * m_fx, s * m_fy, detail::scalePixel(m_cx, s),
      detail::scalePixel(m_cy, s));
}
}  // namespace immslam::camera
