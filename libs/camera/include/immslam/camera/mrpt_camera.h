/* imm-monoslam — conversions between our camera models and MRPT's TCamera / config sections. */
#pragma once

#include <immslam/camera/CCameraModel.h>

#include <optional>
#include <string>

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
/** Our model of an MRPT TCamera: pinhole when every distortion coefficient is zero, otherwise
 * opencv (plumb_bob k1 k2 p1 p2 k3). Throws std::runtime_error if the TCamera is not usable
 * (zero size or focal length) or uses the kannala_brandt model. */
CCameraModel::Ptr fromTCamera(const mrpt::img::TCamera& cam);

/** The TCamera of a model, if MRPT can represent it (pinhole and opencv; davison cannot). */
std::optional<mrpt::img::TCamera> toTCamera(const CCameraModel& cam);

/** Loads an MRPT `[CAMERA_PARAMS]`-style section: `resolution = [W H]`, `cx cy fx fy`,
 * `dist = [k1 k2 p1 p2 k3]` with `distortion_model = plumb_bob` (as written by MRPT's
 * camera-calib), or our extension `model = davison` with `kd1`, or `calib_file = path/calib.txt`.
 * \throws std::runtime_error naming the section and key that is missing or malformed. */
CCameraModel::Ptr loadCameraFromConfig(
    const mrpt::config::CConfigFileBase& cfg, const std::string& section);
}  // namespace immslam::camera
