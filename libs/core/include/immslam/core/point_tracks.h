/* imm-monoslam — point tracks as plain data: tracked positions of features (tracks.csv) and
 * ground-truth points (points_groundtruth.txt, or the renderer's truth at tracked pixels), shared
 * by the simulator, the outputs and evaluation. */
#pragma once

#include <immslam/math/types.h>

#include <cstdint>
#include <limits>

namespace immslam::core
{
/** One tracked position of a dynamic feature (a row of tracks.csv). */
struct TTrackSample
{
  double timestamp = 0;      ///< frame time (s)
  std::int64_t featureId = 0;  ///< the feature's id
  Vec3 p_W = Vec3::Zero();   ///< estimated world position (the estimate's frame and scale)
  Vec2 uv = Vec2::Zero();    ///< measured pixel in that frame
  /** Distance from the camera and its relative 1-sigma (columns `range`, `range_rel_sigma`; NaN
   * when the file has no such column): small for a located point, large for a bearing of unknown
   * depth. */
  double range = std::numeric_limits<double>::quiet_NaN();
  double rangeRelSigma = std::numeric_limits<double>::quiet_NaN();  ///< see range
};

/** One simulated point at one frame (a line of points_groundtruth.txt). */
struct TGroundTruthPoint
{
  double timestamp = 0;          ///< frame time (s)
  std::int64_t pointId = 0;      ///< the point's id
  bool moving = false;           ///< kind: moving (true) or static
  Vec3 p_W = Vec3::Zero();       ///< world position
  Vec2 uv = Vec2::Zero();        ///< its (noisy) projection in that frame
};
}  // namespace immslam::core
