/* imm-monoslam — the Kannala-Brandt ("equidistant") fisheye model of OpenCV's cv::fisheye and MRPT's
 * DistortionModel::kannala_brandt. */
#pragma once

#include <immslam/camera/CCameraModel.h>

namespace immslam::camera
{
/** Kannala-Brandt fisheye projection with four coefficients (calib.txt model
 * `fisheye W H fx fy cx cy k1 k2 k3 k4`), the model of OpenCV's `cv::fisheye`, of MRPT's
 * `TCamera` with `distortion_model = kannala_brandt`, of ROS's `equidistant` and of Kalibr's
 * `pinhole-equi`.
 *
 * The angle of a point \f$ p = (x, y, z) \f$ from the optical axis,
 * \f$ \theta = \operatorname{atan2}(\sqrt{x^2 + y^2}, z) \f$, is distorted to
 * \f$ \theta_d = \theta (1 + k_1 \theta^2 + k_2 \theta^4 + k_3 \theta^6 + k_4 \theta^8) \f$ and
 * \f[ (u, v) = \Big(f_x \theta_d \frac{x}{\sqrt{x^2 + y^2}} + c_x,\;
 *                   f_y \theta_d \frac{y}{\sqrt{x^2 + y^2}} + c_y\Big) \f]
 * (all zero coefficients: the equidistant projection \f$ r = f \theta \f$).
 * Unlike the radial-tangential model the angle, not \f$ \tan\theta \f$, is the variable, so wide
 * lenses (120-180 degrees) are described over the whole image.
 *
 * Valid domain: \f$ \theta < \theta_{max} \f$, the smaller of 90 degrees (every model of this
 * project images points in front of the camera, z > 0) and the first angle where
 * \f$ d\theta_d/d\theta = 1 + 3 k_1 \theta^2 + 5 k_2 \theta^4 + 7 k_3 \theta^6 + 9 k_4 \theta^8 \f$
 * reaches 0 (the map folds back there). project() returns false at or beyond it; pixels beyond
 * the largest \f$ \theta_d \f$ the model produces unproject to the ray at \f$ \theta_{max} \f$.
 * unproject() inverts the odd polynomial by a bracketed Newton iteration to machine precision. */
class CFisheyeCamera : public CCameraModel
{
 public:
  /** \throws std::runtime_error if a size or focal length is not positive or a value not finite. */
  CFisheyeCamera(int width, int height, double fx, double fy, double cx, double cy, double k1, double k2,
                 double k3, double k4);

  std::string modelName() const override { return "fisheye"; }
  std::vector<double> parameters() const override;
  bool project(const Vec3& p_C, Vec2& uv, Mat23* J_uv_p = nullptr) const override;
  math::Bearing unproject(const Vec2& uv, Mat32* J_b_uv = nullptr) const override;
  /** Focal lengths and principal point scale; the coefficients (of angles) are unchanged. */
  Ptr scaled(double s) const override;

  double k1() const { return m_k[0]; }
  double k2() const { return m_k[1]; }
  double k3() const { return m_k[2]; }
  double k4() const { return m_k[3]; }

  /** The largest angle from the optical axis (radians) the model images (see the class comment). */
  double maxAngle() const { return m_thetaMax; }

  /** \f$ \theta_d(\theta) \f$ and, if asked, its derivative. */
  double distortAngle(double theta, double* dThetaD = nullptr) const;
  /** The inverse of distortAngle() on [0, maxAngle()] (clamped to maxAngle() beyond its image);
   * \param clamped set to true when thetaD lies beyond the largest distorted angle. */
  double undistortAngle(double thetaD, bool* clamped = nullptr) const;

 private:
  double m_k[4];
  double m_thetaMax;   //!< valid angles: [0, m_thetaMax)
  double m_thetaDMax;  //!< distortAngle(m_thetaMax)
};
}  // namespace immslam::camera
