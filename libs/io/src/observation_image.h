/* imm-monoslam — private helpers of libs/io: the camera image an MRPT observation carries. */
#pragma once

#include <mrpt/img/CImage.h>
#include <mrpt/img/TCamera.h>
#include <mrpt/obs/CObservation.h>

namespace immslam::io::detail
{
/** An observation's monocular image and its calibration, whatever the observation's class. */
struct TImageView
{
  const mrpt::img::CImage* image = nullptr;   ///< null: the observation carries no camera image
  const mrpt::img::TCamera* camera = nullptr;
};

/** `CObservationImage`: its image and `cameraParams`; `CObservationStereoImages`: the left image and
 * `leftCamera` (a monocular system uses one camera, the left being the stereo pair's reference);
 * `CObservation3DRangeScan` with an intensity image: that image and `cameraParamsIntensity`; any
 * other observation: no image. */
TImageView imageOf(const mrpt::obs::CObservation& o);

/** A TCamera that carries no calibration (default-constructed: zero size or focal length). */
bool isEmptyCamera(const mrpt::img::TCamera& c);
}  // namespace immslam::io::detail
