/* imm-monoslam — one map feature's fused estimate in the world frame (CImmSlamFilter::featureWorldEstimate).
 * Plain data. */
#pragma once

#include <immslam/math/types.h>

namespace immslam::slam
{
/** A feature's fused estimate expressed in the world frame (for maps, scenes and overlays). The
 * covariances are those of the feature relative to the current camera (the camera pose's own
 * uncertainty is not added). */
struct TFeatureWorldEstimate
{
  Vec3 p_W = Vec3::Zero();      ///< mean position (inverse depth: anchor + m / max(rho, 1e-3))
  Mat3 cov_W = Mat3::Zero();    ///< covariance of p_W (first order; for inverse depth its Euclidean approximation)
  bool depthKnown = false;
  bool inverseDepth = false;
  Vec3 anchor_W = Vec3::Zero(); ///< inverse depth: anchor in W
  double theta = 0, phi = 0, rho = 0;  ///< inverse depth: ray angles in W and inverse depth
  Mat3 cov_tpr = Mat3::Zero();  ///< inverse depth: covariance of (theta, phi, rho) in W
};
}  // namespace immslam::slam
