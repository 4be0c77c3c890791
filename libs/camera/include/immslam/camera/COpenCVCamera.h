/* imm-monoslam — OpenCV's radial-tangential ("plumb bob") camera model. */
#pragma once

#include <immslam/camera/CCameraModel.h>

namespace immslam::camera
{
/** OpenCV radial-tangential distortion (k1 k2 p1 p2 k3), undistorted -> distorted.
 *
 * With the normalized point \f$ (x, y) = (X/Z, Y/Z) \f$, \f$ r^2 = x^2 + y^2 \f$ and
 * \f$ R = 1 + k_1 r^2 + k_2 r^4 + k_3 r^6 \f$:
 * \f[ x_d = x R + 2 p_1 x y + p_2 (r^2 + 2 x^2), \quad
 *     y_d = y R + p_1 (r^2 + 2 y^2) + 2 p_2 x y, \f]
 * then \f$ u = f_x x_d + c_x,\; v = f_y y_d + c_y \f$ (calib.txt model
 * `opencv W H fx fy cx cy k1 k2 p1 p2 k3`).
 *
 * Valid domain: the radial map \f$ r \mapsto r R(r^2) \f$ folds back at large radii for some
 * coefficients (\f$ d r_d / d r = 1 + 3 k_1 r^2 + 5 k_2 r^4 + 7 k_3 r^6 \f$ reaches 0). The first
 * such radius is computed at construction (maxUndistortedRadius()); project() returns false at
 * or beyond it and unproject() never returns a ray beyond it.
 *
 * unproject() solves the distortion by a bracketed 1-D Newton on the radial part (a start inside
 * the valid domain) followed by 2-D Newton steps on the full model with its analytic 2x2
 * Jacobian, to machine precision (a few iterations). */
class COpenCVCamera : public CCameraModel
{
 public:
  /** \throws std::runtime_error if a size or focal length is not positive or a value not finite. */
  COpenCVCamera(int width, int height, double fx, double fy, double cx, double cy, double k1,
      double k2, double p1, double p2, double k3);

  std::string modelName() const override { return "opencv"; }
  std::vector<double> parameters() const override;
  bool project(const Vec3& p_C, Vec2& uv, Mat23* J_uv_p = nullptr) const override;
  /** Pixels whose distorted radius lies beyond the largest one the model can produce (only for
   * folding coefficients) map to the ray at the fold radius. */
  math::Bearing unproject(const Vec2& uv, Mat32* J_b_uv = nullptr) const override;
  /** Focal lengths and principal point scale, distortion coefficients are unchanged. */
  Ptr scaled(double s) const override;

  /** Radial coefficient of \f$ r^2 \f$. */
  double k1() const { return m_k1; }
  /** Radial coefficient of \f$ r^4 \f$. */
  double k2() const { return m_k2; }
  /** First tangential coefficient. */
  double p1() const { return m_p1; }
  /** Second tangential coefficient. */
  double p2() const { return m_p2; }
  /** Radial coefficient of \f$ r^6 \f$. */
  double k3() const { return m_k3; }

  /** The largest normalized undistorted radius \f$ \sqrt{x^2+y^2} \f$ up to which the radial
   * map is monotone (+infinity if it is monotone everywhere). */
  double maxUndistortedRadius() const { return m_rMax; }

  /** Applies the distortion to a normalized point. \param J_d_n d(xd, yd)/d(x, y), 2x2. */
  Vec2 distort(const Vec2& n, Mat2* J_d_n = nullptr) const;

  /** Inverts distort(): the normalized undistorted point of a normalized distorted one. */
  Vec2 undistort(const Vec2& nd) const;

 private:
  double m_k1, m_k2, m_p1, m_p2, m_k3;
  double m_rMax;   //!< fold radius (normalized, undistorted), +inf if none
  double m_r2Max;  //!< m_rMax^2
};
}  // namespace immslam::camera
