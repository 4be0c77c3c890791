/* imm-monoslam — the shadow filter's held-back matches (see CHeldBackMatches.h). */
#include <immslam/system/CHeldBackMatches.h>

namespace immslam::system
{
std::vector<CHeldBackMatches::TMatch> CHeldBackMatches::update(std::size_t frame, const shadow::TShadowReport* srep,
                                                               const slam::CMonoSlamIMM& slam)
{
  std::unordered_set<std::int64_t> inSlam, used;
  for (const auto& feat : slam.features()) inSlam.insert(feat.id);
  for (const auto& sr : slam.lastReport().searches)
    if (sr.status == slam::TSearchRecord::EStatus::LowInnovationInlier ||
        sr.status == slam::TSearchRecord::EStatus::RescuedInlier)
      used.insert(sr.id);
  return update(frame, srep, inSlam, used);
}

std::vector<CHeldBackMatches::TMatch> CHeldBackMatches::update(std::size_t frame, const shadow::TShadowReport* srep,
                                                               const std::unordered_set<std::int64_t>& inSlam,
                                                               const std::unordered_set<std::int64_t>& slamUsed)
{
  std::vector<TMatch> out;
  // Features SLAM took: out once SLAM has used them kConfirmUpdates times; dropped when SLAM
  // deletes them before.
  for (auto it = m_confirming.begin(); it != m_confirming.end();)
  {
    if (!inSlam.count(it->first))
    {
      it = m_confirming.erase(it);
      continue;
    }
    it->second.first += slamUsed.count(it->first) ? 1 : 0;
    if (it->second.first >= kConfirmUpdates)
    {
      out.insert(out.end(), it->second.second.begin(), it->second.second.end());
      it = m_confirming.erase(it);
    }
    else
      ++it;
  }
  if (!srep) return out;
  std::unordered_set<std::int64_t> seen;
  for (const auto& v : srep->views)
  {
    seen.insert(v.id);
    if (v.cls != shadow::EShadowClass::Pending)
    {
      m_held.erase(v.id);  // decided dynamic, or seen moving: never static
      continue;
    }
    if (!v.measured || (inSlam.count(v.id) && !m_held.count(v.id))) continue;  // a probation copy
    m_held[v.id].push_back({frame, v.id, v.uv});
  }
  const auto handOver = [&](std::int64_t id) {
    const auto it = m_held.find(id);
    if (it == m_held.end()) return;
    if (inSlam.count(id))
      m_confirming[id] = {0, std::move(it->second)};
    else  // a watched feature retired: SLAM never measures it
      out.insert(out.end(), it->second.begin(), it->second.end());
    m_held.erase(it);
  };
  // Decided static in this frame (promoted, or retired): it has left the shadow filter's views, and
  // its pixel of this frame is the decision's.
  for (const auto& d : srep->decisions)
  {
    if (d.cls != shadow::EShadowClass::Static || !m_held.count(d.id)) continue;
    m_held[d.id].push_back({frame, d.id, d.uv});
    seen.insert(d.id);
    handOver(d.id);
  }
  // Released into SLAM undecided (SLAM short of features), or gone (lost, timed out).
  std::vector<std::int64_t> ids;
  ids.reserve(m_held.size());
  for (const auto& held : m_held) ids.push_back(held.first);
  for (const std::int64_t id : ids)
    if (inSlam.count(id))
      handOver(id);
    else if (!seen.count(id))
      m_held.erase(id);
  return out;
}
}  // namespace immslam::system
