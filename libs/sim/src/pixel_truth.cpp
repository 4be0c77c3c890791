/* imm-monoslam — ground truth at tracked pixels of a rendered sequence (see pixel_truth.h). */
#include <immslam/sim/pixel_truth.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>

namespace immslam::sim
{
std::vector<core::TGroundTruthPoint> truthAtPixels(const CSimulator& sim, const std::vector<core::TTrackSample>& samples,
                                                   double maxDt, double boundaryPx, double depthStep,
                                                   TPixelTruthStats* stats)
{
  TPixelTruthStats st;
  st.samples = samples.size();
  std::vector<double> times(sim.frameCount());
  for (std::size_t k = 0; k < times.size(); ++k) times[k] = sim.timestamp(k);
  std::vector<core::TGroundTruthPoint> out;
  out.reserve(samples.size());
  for (std::size_t s = 0; s < samples.size(); ++s)
  {
    const core::TTrackSample& smp = samples[s];
    // Nearest frame by timestamp (the timestamps increase with k).
    const auto it = std::lower_bound(times.begin(), times.end(), smp.timestamp);
    std::size_t k = static_cast<std::size_t>(it - times.begin());
    if (k == times.size() || (k > 0 && smp.timestamp - times[k - 1] < times[k] - smp.timestamp)) --k;
    if (times.empty() || !(std::abs(times[k] - smp.timestamp) <= maxDt))
    {
      ++st.noFrame;
      continue;
    }
    const auto hit = sim.raycast(k, smp.uv);
    if (!hit)
    {
      ++st.boundary;
      continue;
    }
    bool edge = false;
    for (int d = 0; d < 8 && !edge; ++d)
    {
      const double a = d * M_PI / 4;
      const auto h = sim.raycast(k, smp.uv + boundaryPx * Vec2(std::cos(a), std::sin(a)));
      edge = !h || h->objectId != hit->objectId || std::abs(h->depth - hit->depth) > depthStep * hit->depth;
    }
    if (edge)
    {
      ++st.boundary;
      continue;
    }
    core::TGroundTruthPoint p;
    p.timestamp = times[k];
    p.pointId = static_cast<std::int64_t>(s);
    p.moving = hit->objectId > 0 && hit->moving;
    p.p_W = hit->p_W;
    p.uv = smp.uv;
    (p.moving ? st.onMoving : st.onStatic)++;
    out.push_back(p);
  }
  if (stats) *stats = st;
  return out;
}

std::vector<core::TGroundTruthPoint> truthAtPixelsOfRenderedFolder(const std::string& folder,
                                                                   const std::vector<core::TTrackSample>& samples,
                                                                   double maxDt, TPixelTruthStats* stats)
{
  const std::filesystem::path ini = std::filesystem::path(folder) / "scenario.ini";
  if (!std::filesystem::is_regular_file(ini))
    throw std::runtime_error("'" + folder + "' has no scenario.ini: not a folder written by imm-render");
  const CSimulator sim(TScenario::loadFile(ini.string()));
  return truthAtPixels(sim, samples, maxDt, 2.0, 0.05, stats);
}
}  // namespace immslam::sim
