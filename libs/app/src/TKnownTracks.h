/* imm-monoslam — private to libs/app: [input] known_association, the measured point tracks by frame
 * time. */
#pragma once

#include <immslam/core/point_tracks.h>
#include <immslam/math/types.h>

#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace immslam::app::detail
{
/** [input] known_association: the measured point tracks, by frame time. */
struct TKnownTracks
{
  std::map<long long, std::vector<std::pair<std::int64_t, Vec2>>> byTime;  ///< microseconds -> (track, pixel)
  std::set<std::int64_t> moving;                                            ///< tracks of kind moving

  /** The points of `kinds` (`all`, `static` or `moving`, [input] known_association_kinds), by time.
   * \param used set to the number of measurements kept. */
  static TKnownTracks fromPoints(const std::vector<core::TGroundTruthPoint>& points, const std::string& kinds,
                                 std::size_t& used);

  /** The tracks of the frame at t (within 0.1 ms), in the pixels of the image reduced by `factor`;
   * staticOnly: without the moving ones (a static first map). */
  std::vector<std::pair<std::int64_t, Vec2>> at(double t, int factor, bool staticOnly) const;
};
}  // namespace immslam::app::detail
