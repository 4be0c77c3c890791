/* imm-monoslam — [input] known_association (see TKnownTracks.h). */
#include "TKnownTracks.h"

#include <cmath>

namespace immslam::app::detail
{
TKnownTracks TKnownTracks::fromPoints(const std::vector<core::TGroundTruthPoint>& points, const std::string& kinds,
                                      std::size_t& used)
{
  TKnownTracks tracks;
  used = 0;
  for (const auto& p : points)
    if (kinds == "all" || (kinds == "moving") == p.moving)
    {
      tracks.byTime[std::llround(p.timestamp * 1e6)].emplace_back(p.pointId, p.uv);
      if (p.moving) tracks.moving.insert(p.pointId);
      ++used;
    }
  return tracks;
}

std::vector<std::pair<std::int64_t, Vec2>> TKnownTracks::at(double t, int factor, bool staticOnly) const
{
  std::vector<std::pair<std::int64_t, Vec2>> z;
  const long long us = std::llround(t * 1e6);
  for (auto it = byTime.lower_bound(us - 100); it != byTime.end() && it->first <= us + 100; ++it)
    for (const auto& [id, uv] : it->second)
      if (!staticOnly || !moving.count(id)) z.emplace_back(id, factor > 1 ? Vec2(uv / factor) : uv);
  return z;
}
}  // namespace immslam::app::detail
