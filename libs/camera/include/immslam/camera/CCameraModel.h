/* imm-monoslam — camera intrinsic models behind one interface.
 *
 * Pixel convention: (u, v) = (0, 0) is the centre of the top-left pixel, u right, v down.
 * Camera frame: optical frame, x right, y down, z forward (doc/conventions.md).
 */
#pragma once

#include <immslam/math/bearing.h>
#include <immslam/math/types.h>

#include <memory>
#include <string>
#include <vector>

namespace immslam::camera
{
/** A calibrated camera: projection with distortion and unprojection to a bearing, both with
 * analytic Jacobians (checked against numerical ones in camera_unittest).
 *
 * Implementations: CPinholeCamera, COpenCVCamera (radial-tangential k1 k2 p1 p2 k3),
 * CDavisonCamera (one-parameter wide-angle model of MonoSLAM, see ../shared/data/README.md),
 * CFisheyeCamera (Kannala-Brandt, OpenCV's cv::fisheye, MRPT's kannala_brandt).
 * Objects are immutable and shared through Ptr. */
class CCameraModel
{
 public:
  using Ptr = std::shared_ptr<const CCameraModel>;

  virtual ~CCameraModel() = default;

  /** The calib.txt model word: "pinhole", "opencv", "davison" or "fisheye". */
  virtual std::string modelName() const = 0;

  /** Parameters after the image size, in calib.txt order (fx fy cx cy [distortion...]). */
  virtual std::vector<double> parameters() const = 0;

  /** Projects a point in the camera frame to distorted pixels.
   * Only the direction of p_C matters (p_C may be a homogeneous/scaled point, e.g. the
   * inverse-depth \f$ h^C = R_{CW}(\rho(x_0 - r) + m) \f$).
   * \param J_uv_p d(uv)/d(p_C), 2x3.
   * \return false if the point is not in front of the camera (z <= 1e-9 |p|) or the distortion
   * model is not valid there (uv is then left unspecified). Does not check the image bounds. */
  virtual bool project(const Vec3& p_C, Vec2& uv, Mat23* J_uv_p = nullptr) const = 0;

  /** Unprojects a distorted pixel to its viewing direction (z > 0) in the camera frame.
   * \param J_b_uv d(unit vector)/d(uv), 3x2. */
  virtual math::Bearing unproject(const Vec2& uv, Mat32* J_b_uv = nullptr) const = 0;

  /** The same model for the image resampled by factor s (0.5: half resolution). */
  virtual Ptr scaled(double s) const = 0;

  int width() const { return m_width; }
  int height() const { return m_height; }
  double fx() const { return m_fx; }
  double fy() const { return m_fy; }
  double cx() const { return m_cx; }
  double cy() const { return m_cy; }

  /** True if uv lies inside the image with at least `margin` pixels to every border.
   * The image covers \f$ [-0.5, W - 0.5] \times [-0.5, H - 0.5] \f$ (pixel centres at integers), so
   * with margin = h the (2h+1)^2 patch centred on the pixel nearest to uv lies inside the image. */
  bool isInImage(const Vec2& uv, double margin = 0.0) const;

  /** True if the lens images the pixel uv: its ray (unproject) is in front of the camera and projects
   * back onto uv (within 0.05 px). False outside a fisheye's image circle beyond 90 degrees or beyond
   * a distortion's fold, where unproject() returns the limit ray. \param ray if given, the unit ray. */
  bool imagesPixel(const Vec2& uv, Vec3* ray = nullptr) const;

  /** One line of calib.txt: "MODEL W H PARAMS..." (full precision). */
  std::string toCalibLine() const;

 protected:
  CCameraModel(int width, int height, double fx, double fy, double cx, double cy);

  int m_width, m_height;
  double m_fx, m_fy, m_cx, m_cy;
};

/** Parses one calib.txt model line ("pinhole 320 240 fx fy cx cy", "opencv W H fx fy cx cy k1 k2
 * p1 p2 k3", "davison W H fx fy cx cy kd1").
 * \param context named in errors, e.g. "calib.txt:3".
 * \throws std::runtime_error naming the context and what is wrong. */
CCameraModel::Ptr parseCalibLine(const std::string& line, const std::string& context);

/** Loads a calib.txt file (one non-comment line; '#' comments and blank lines are skipped).
 * \throws std::runtime_error naming the file and line. */
CCameraModel::Ptr loadCalibFile(const std::string& path);

/** A guess for a camera without calibration: a pinhole of the given image size whose horizontal
 * field of view is `hfovDeg`, fx = fy = (W / 2) / tan(hfov / 2), principal point at the image centre
 * ((W - 1) / 2, (H - 1) / 2 in the pixel-centre convention), no distortion.
 * \throws std::invalid_argument unless W, H > 0 and 1 <= hfovDeg <= 179. */
CCameraModel::Ptr pinholeFromFieldOfView(int width, int height, double hfovDeg);

/** Writes a calib.txt file with a comment header. */
void saveCalibFile(const CCameraModel& cam, const std::string& path);

/** Builds a model from its name and parameters (as parseCalibLine, already split). */
CCameraModel::Ptr makeCameraModel(
    const std::string& model, int width, int height, const std::vector<double>& params);
}  // namespace immslam::camera
