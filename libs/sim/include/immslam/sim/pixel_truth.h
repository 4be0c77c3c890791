/* imm-monoslam — ground truth at the pixels of tracked features of a rendered sequence (issue 5:
 * position error of the shadow filter's tracks on the renderer's scenes). */
#pragma once

#include <immslam/core/point_tracks.h>
#include <immslam/sim/CSimulator.h>

#include <cstddef>
#include <string>
#include <vector>

namespace immslam::sim
{
/** What truthAtPixels() found. */
struct TPixelTruthStats
{
  std::size_t samples = 0;    ///< rows given
  std::size_t noFrame = 0;    ///< no rendered frame within maxDt of the row's timestamp
  std::size_t boundary = 0;   ///< pixel within boundaryPx of a silhouette or depth step: no single truth
  std::size_t onMoving = 0;   ///< truth is a point of a moving object
  std::size_t onStatic = 0;   ///< truth is a point of the static world
};

/** The true 3-D point seen at the measured pixel of each tracked sample (tracks.csv row): the ray
 * of pixel uv in the frame of the row's timestamp, cast through the scenario's world with the
 * camera and the objects at their true poses (CSimulator::raycast, exactly the renderer's
 * geometry). Returned as ground-truth points in the format of eval::readPointsGroundTruth() (one
 * per usable sample, at the sample's own pixel, kind `moving` for a moving object's surface), to be
 * scored with eval::trackErrorAgainstPoints() with a sub-pixel radius.
 * A corner on an object's silhouette is where two surfaces at different depths meet (a
 * T-junction: no physical point), so a sample is left out (TPixelTruthStats::boundary) when a ray
 * boundaryPx away in any of 8 directions hits another object or a depth differing by more than
 * depthStep (relative).
 * \param maxDt largest difference between a sample's timestamp and its frame's. */
std::vector<core::TGroundTruthPoint> truthAtPixels(const CSimulator& sim, const std::vector<core::TTrackSample>& samples,
                                                   double maxDt = 1e-4, double boundaryPx = 2.0,
                                                   double depthStep = 0.05, TPixelTruthStats* stats = nullptr);

/** truthAtPixels() for a dataset folder written by imm-render: the simulator is rebuilt from the
 * folder's scenario.ini (the effective scenario it was rendered from).
 * \throws std::runtime_error naming the folder when it has no scenario.ini, or the scenario's error. */
std::vector<core::TGroundTruthPoint> truthAtPixelsOfRenderedFolder(const std::string& folder,
                                                                   const std::vector<core::TTrackSample>& samples,
                                                                   double maxDt = 1e-4,
                                                                   TPixelTruthStats* stats = nullptr);
}  // namespace immslam::sim
