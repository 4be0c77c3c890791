/* imm-monoslam — prediction of the camera-centred SLAM state (Civera et al.'s camera-centred EKF):
 * the camera moves by the increment of its motion model and the whole state is re-expressed in the
 * new camera frame: the world pose T_C_W, the velocities and every feature. */
#pragma once

#include <immslam/bayes/CIMMEstimator.h>
#include <immslam/motion/motion_models.h>
#include <immslam/slam/TFeature.h>

#include <vector>

namespace immslam::slam
{
/** \f$ x' = f(x, u + n) \f$ and \f$ P' = A (P + E N E^\top) A^\top \f$, with A = df/dx block-structured
 * (each block depends on itself and on the velocities u only), computed block by block in
 * O(n sum_b (s_b^2 + 6 s_b)). The stationary model leaves the map and world pose untouched and zeroes
 * the velocities. \param scratch an n x n buffer reused between calls. */
void predictRobocentric(bayes::TGaussian& g, const std::vector<TFeature>& features,
                        const motion::TMotionIncrement& inc, MatX& scratch);
}  // namespace immslam::slam
