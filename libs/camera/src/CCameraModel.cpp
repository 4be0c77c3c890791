/* imm-monoslam — the camera model base: validation, image bounds, calib.txt line. */
#include <immslam/camera/CCameraModel.h>

#include "camera_detail.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <stdexcept>

namespace immslam::camera
{
namespace detail
{
std::string exactText(double v)
{
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof(buf), v);
  return std::string(buf, res.ptr);
}

void checkScale(double s, const std::string& model)
{
  if (!(s > 0) || !std::isfinite(s))
    throw std::runtime_error(model + " camera: scale factor must be positive and finite, got " +
                             detail::exactText(s));
}

int scaleSize(int n, double s) { return std::max(1, static_cast<int>(std::lround(s * n))); }
}  // namespace detail

CCameraModel::CCameraModel(int width, int height, double fx, double fy, double cx, double cy)
    : m_width(width), m_height(height), m_fx(fx), m_fy(fy), m_cx(cx), m_cy(cy)
{
  if (width <= 0) throw std::runtime_error("camera: width must be positive, got " + std::to_string(width));
  if (height <= 0)
    throw std::runtime_error("camera: height must be positive, got " + std::to_string(height));
  if (!(fx > 0) || !std::isfinite(fx))
    throw std::runtime_error("camera: fx must be positive and finite, got " + detail::exactText(fx));
  if (!(fy > 0) || !std::isfinite(fy))
    throw std::runtime_error("camera: fy must be positive and finite, got " + detail::exactText(fy));
  if (!std::isfinite(cx)) throw std::runtime_error("camera: cx must be finite, got " + detail::exactText(cx));
  if (!std::isfinite(cy)) throw std::runtime_error("camera: cy must be finite, got " + detail::exactText(cy));
}

bool CCameraModel::isInImage(const Vec2& uv, double margin) const
{
  return uv.x() >= margin - 0.5 && uv.x() <= m_width - 0.5 - margin && uv.y() >= margin - 0.5 &&
         uv.y() <= m_height - 0.5 - margin;
}

bool CCameraModel::imagesPixel(const Vec2& uv, Vec3* ray) const
{
  const Vec3 b = unproject(uv).unitVector();
  if (ray) *ray = b;
  Vec2 back;
  return b.allFinite() && b.z() > 0 && project(b, back) && (back - uv).norm() < 0.05;
}

std::string CCameraModel::toCalibLine() const
{
  std::string line = modelName() + " " + std::to_string(m_width) + " " + std::to_string(m_height);
  for (const double p : parameters()) line += " " + detail::exactText(p);
  return line;
}
}  // namespace immslam::camera
