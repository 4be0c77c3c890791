/* imm-monoslam — the ideal pinhole camera (no lens distortion). */
#pragma once

#include <immslam/camera/CCameraModel.h>

namespace immslam::camera
{
/** Ideal pinhole camera: \f$ u = f_x x/z + c_x,\; v = f_y y/z + c_y \f$ (calib.txt model
 * `pinhole W H fx fy cx cy`). */
class CPinholeCamera : public CCameraModel
{
 public:
  /** \throws std::runtime_error if a size or focal length is not positive or a value not finite. */
  CPinholeCamera(int width, int height, double fx, double fy, double cx, double cy);

  std::string modelName() const override { return "pinhole"; }
  std::vector<double> parameters() const override;
  bool project(const Vec3& p_C, Vec2& uv, Mat23* J_uv_p = nullptr) const override;
  math::Bearing unproject(const Vec2& uv, Mat32* J_b_uv = nullptr) const override;
  Ptr scaled(double s) const override;
};
}  // namespace immslam::camera
