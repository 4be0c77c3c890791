/* imm-monoslam — Davison's one-parameter wide-angle model (MonoSLAM). */
#pragma once

#include <immslam/camera/CCameraModel.h>

namespace immslam::camera
{
/** MonoSLAM's wide-angle model, in pixels around the principal point (calib.txt model
 * `davison W H fx fy cx cy kd1`, see ../shared/data/README.md).
 *
 * The undistorted pixel offset \f$ a = (f_x x/z,\; f_y y/z) \f$, \f$ r_u = |a| \f$, is shrunk to
 * \f$ r_d = r_u / \sqrt{1 + 2 k_{d1} r_u^2} \f$:
 * \f$ (u, v) = (c_x, c_y) + a / \sqrt{1 + 2 k_{d1} r_u^2} \f$; inversely
 * \f$ r_u = r_d / \sqrt{1 - 2 k_{d1} r_d^2} \f$ (the wide-angle model of refs. [11], [12] of
 * the MonoSLAMBOT paper: Davison, Cid, Kita, "Real-time 3D SLAM with wide-angle vision", 2004).
 *
 * Valid domain: for \f$ k_{d1} > 0 \f$ every ray in front projects (\f$ r_d < 1/\sqrt{2 k_{d1}} \f$)
 * and pixels near or beyond that radius (where \f$ 1 - 2 k_{d1} r_d^2 < 10^{-6} \f$) unproject as
 * if it were \f$ 10^{-6} \f$: very oblique rays (nearly 90 degrees), z > 0, finite; for \f$ k_{d1} < 0 \f$ project() returns false when
 * \f$ 1 + 2 k_{d1} r_u^2 \le 10^{-12} \f$. */
class CDavisonCamera : public CCameraModel
{
 public:
  /** \throws std::runtime_error if a size or focal length is not positive or a value not finite. */
  CDavisonCamera(int width, int height, double fx, double fy, double cx, double cy, double kd1);

  std::string modelName() const override { return "davison"; }
  std::vector<double> parameters() const override;
  bool project(const Vec3& p_C, Vec2& uv, Mat23* J_uv_p = nullptr) const override;
  math::Bearing unproject(const Vec2& uv, Mat32* J_b_uv = nullptr) const override;
  /** kd1 scales by \f$ 1/s^2 \f$ (the model is in pixels). */
  Ptr scaled(double s) const override;

  /** The distortion coefficient (1/px^2). */
  double kd1() const { return m_kd1; }

 private:
  double m_kd1;
};
}  // namespace immslam::camera
