/* imm-monoslam — the SLAM map's measured pixels over recent frames (CMapViews). */
#include <immslam/shadow/CMapViews.h>

#include <algorithm>

namespace immslam::shadow
{
namespace
{
/** The pixel of feature id in a frame's measurements (sorted by id), or null. */
const Vec2* pixelOf(const std::vector<std::pair<std::int64_t, Vec2>>& z, std::int64_t id)
{
  const auto it = std::lower_bound(z.begin(), z.end(), id, [](const auto& m, std::int64_t v) { return m.first < v; });
  return it != z.end() && it->first == id ? &it->second : nullptr;
}
}  // namespace

void CMapViews::add(std::int64_t frame, std::vector<std::pair<std::int64_t, Vec2>> z)
{
  if (!m_frames.empty() && frame <= m_frames.back().first) return;  // (a frame given twice keeps its first)
  std::sort(z.begin(), z.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  m_frames.emplace_back(frame, std::move(z));
  while (m_frames.size() > kFrames) m_frames.pop_front();
}

const CMapViews::TFrame* CMapViews::find(std::int64_t frame) const
{
  const auto it = std::lower_bound(m_frames.begin(), m_frames.end(), frame,
                                   [](const TFrame& f, std::int64_t v) { return f.first < v; });
  return it != m_frames.end() && it->first == frame ? &*it : nullptr;
}

std::vector<std::array<Vec2, 3>> CMapViews::common(const std::array<std::int64_t, 3>& frames, std::size_t maxCount) const
{
  const TFrame* f[3] = {find(frames[0]), find(frames[1]), find(frames[2])};
  std::vector<std::array<Vec2, 3>> all;
  if (!f[0] || !f[1] || !f[2]) return all;
  for (const auto& [id, uv0] : f[0]->second)
  {
    const Vec2* uv1 = pixelOf(f[1]->second, id);
    const Vec2* uv2 = uv1 ? pixelOf(f[2]->second, id) : nullptr;
    if (uv2) all.push_back({uv0, *uv1, *uv2});
  }
  if (all.size() <= maxCount) return all;
  std::vector<std::array<Vec2, 3>> spread;
  for (std::size_t i = 0; i < maxCount; ++i) spread.push_back(all[i * all.size() / maxCount]);
  return spread;
}
}  // namespace immslam::shadow
