/* imm-monoslam — conversions between our camera models and MRPT's TCamera / config sections. */
#pragma once

#include <immslam/camera/CCameraModel.h>

#include <optional>
#include <string>
#include <vector>

namespace mrpt::img
{
class TCamera;
}
namespace mrpt::config
{
class CConfigFileBase;
}

namespace immslam::camera
{
/** Our model of an MRPT TCamera: plumb_bob -> pinhole when every distortion coefficient is zero,
 * otherwise opencv (k1 k2 p1 p2 k3); kannala_brandt -> fisheye (k1 k2 k3 k4). Throws
 * std::runtime_error if the TCamera is not usable (zero size or focal length) or uses the rational
 * coefficients k4 k5 k6 of plumb_bob. */
CCameraModel::Ptr fromTCamera(const mrpt::img::TCamera& cam);

/** The TCamera of a model, if MRPT can represent it (pinhole, opencv, fisheye; davison cannot). */
std::optional<mrpt::img::TCamera> toTCamera(const CCameraModel& cam);

/** Loads an MRPT `[CAMERA_PARAMS]`-style section: `resolution = [W H]`, `cx cy fx fy`,
 * `dist = [k1 k2 p1 p2 k3]` with `distortion_model = plumb_bob` (as written by MRPT's
 * camera-calib), `dist = [k1 k2 k3 k4]` with `distortion_model = kannala_brandt` (fisheye), or our
 * extension `model = davison` with `kd1`, or `calib_file = path/calib.txt`.
 *
 * Rules, in order:
 * - `calib_file = PATH` (relative to the current directory) takes precedence: the model is that
 *   calib.txt file's and every other key is ignored.
 * - `resolution`, `fx`, `fy`, `cx`, `cy` are required. As in MRPT's TCamera, a value below 2 is a
 *   fraction of the image size (fx, cx times the width; fy, cy times the height).
 * - `model = pinhole | opencv | davison | fisheye` (our extension) selects the model: opencv needs
 *   `dist` (4, 5 or 8 values k1 k2 p1 p2 [k3 [k4 k5 k6]], k4..k6 zero), fisheye `dist` (4 values
 *   k1 k2 k3 k4), davison needs `kd1` (1/px^2), pinhole accepts `dist` only if all zero.
 * - Without `model`, MRPT's `distortion_model` decides: `plumb_bob` -> opencv with `dist` required
 *   (pinhole if all coefficients are zero), `none` -> pinhole (`dist` ignored, as MRPT does),
 *   `kannala_brandt` -> fisheye with `dist` = [k1 k2 k3 k4] required; without `distortion_model` (MRPT 1.x files), a `dist` with a
 *   non-zero coefficient means opencv, otherwise pinhole.
 * Other keys are not read (`camera_name`, `focal_length`, ...); cameraConfigKeys() lists the
 * understood ones for callers that validate their sections.
 * \throws std::runtime_error naming the section and key that is missing or malformed. */
CCameraModel::Ptr loadCameraFromConfig(
    const mrpt::config::CConfigFileBase& cfg, const std::string& section);

/** The keys loadCameraFromConfig() understands, plus those MRPT's TCamera writes
 * (`camera_name`, `focal_length`), e.g. to reject unknown keys in a camera section. */
std::vector<std::string> cameraConfigKeys();
}  // namespace immslam::camera
