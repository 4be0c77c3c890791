/* imm-monoslam — the camera image an MRPT observation carries. */
#include "observation_image.h"

#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationImage.h>
#include <mrpt/obs/CObservationStereoImages.h>

namespace immslam::io::detail
{
TImageView imageOf(const mrpt::obs::CObservation& o)
{
  using namespace mrpt::obs;
  if (const auto* im = dynamic_cast<const CObservationImage*>(&o)) return {&im->image, &im->cameraParams};
  if (const auto* st = dynamic_cast<const CObservationStereoImages*>(&o)) return {&st->imageLeft, &st->leftCamera};
  if (const auto* r3 = dynamic_cast<const CObservation3DRangeScan*>(&o))
    if (r3->hasIntensityImage) return {&r3->intensityImage, &r3->cameraParamsIntensity};
  return {};
}

bool isEmptyCamera(const mrpt::img::TCamera& c)
{
  return c.ncols == 0 || c.nrows == 0 || !(c.fx() > 0) || !(c.fy() > 0);
}
}  // namespace immslam::io::detail
