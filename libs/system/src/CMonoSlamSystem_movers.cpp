/* imm-monoslam — CMonoSlamSystem: features that turn out to move after they were mapped (the
 * handover of SLAM features rejected frame after frame, the probation of a first map) and the
 * mapped past their dynamic tracks start with (doc/shadow.md, "Movers in the map"). */
#include <immslam/math/quaternion.h>
#include <immslam/system/CMonoSlamSystem.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>
#include <unordered_set>

namespace immslam::system
{
namespace
{
/** Camera centres kept for the ranges of mapped pasts (frames). */
constexpr std::size_t kCameraPathFrames = 600;
}  // namespace

void CMonoSlamSystem::endFrame(double timestamp)
{
  m_cameraPath.emplace_back(timestamp, m_slam->cameraPosition());
  if (m_cameraPath.size() > kCameraPathFrames) m_cameraPath.pop_front();
  m_prevR = m_slam->cameraPosition();
  m_prevQ = m_slam->cameraOrientation();
}

std::vector<std::pair<std::int64_t, std::int64_t>> CMonoSlamSystem::handOver(const slam::TFrameReport& rep,
                                                                              const cv::Mat& grey)
{
  // SLAM features rejected frame after frame: handed back to the shadow filter at their pixel.
  std::vector<std::pair<std::int64_t, std::int64_t>> moved;
  if (m_opts.handover_rejections <= 0) return moved;
  // A feature on probation has its copy in the shadow filter already: the copy goes on as an
  // ordinary pending feature. The others enter as new pending features (a new id: decided static
  // again, a point that moved and stopped is a new map point, not the old one).
  std::unordered_map<std::int64_t, std::int64_t> copyOf;
  for (const auto& [copy, id] : m_probation) copyOf[id] = copy;
  std::vector<std::int64_t> drop, ids;
  std::vector<Vec2> at;
  std::vector<std::vector<TMappedPast>> pasts;
  for (const auto& s : rep.searches)
    if (s.status == slam::TSearchRecord::EStatus::Rejected)
      for (const auto& f : m_slam->features())
        if (f.id == s.id && f.rejectedInRow >= m_opts.handover_rejections)
        {
          drop.push_back(f.id);
          const auto c = copyOf.find(f.id);
          if (c != copyOf.end())
          {
            m_pastOf[c->second] = mappedPast(f, c->second);
            m_probation.erase(c->second);
            m_shadow->setMapCopies({c->second}, false);
            moved.emplace_back(f.id, c->second);
            continue;
          }
          pasts.push_back(mappedPast(f, -1));
          at.push_back(s.z);
          ids.push_back(f.id);
        }
  if (drop.empty()) return moved;
  m_slam->removeFeatures(drop);
  const auto added = m_shadow->addFeatures(grey, at);
  m_frame.handedOver = static_cast<int>(drop.size());
  for (std::size_t k = 0; k < ids.size(); ++k)
  {
    moved.emplace_back(ids[k], added[k]);
    if (added[k] < 0) continue;
    for (auto& row : pasts[k]) row.id = added[k];
    m_pastOf[added[k]] = std::move(pasts[k]);
  }
  return moved;
}

bool CMonoSlamSystem::pixelOf(const slam::TFeature& f, Vec2& uv) const
{
  const Vec3 p_C = math::quatRotate(math::quatConjugate(m_slam->cameraOrientation()),
                                    m_slam->featurePosition(f) - m_slam->cameraPosition());
  return m_slam->camera().project(p_C, uv) && m_slam->camera().isInImage(uv);
}

void CMonoSlamSystem::startProbation(const cv::Mat& grey, const std::vector<std::int64_t>& slamIds)
{
  // A first map takes whatever is in view, movers included. Each of its features gets a copy in the
  // shadow filter at its pixel, classified like any pending feature (the depth-free test while the
  // camera does not translate, the three-ray test when it does): the map holds a mover only until
  // its copy is decided dynamic.
  const std::unordered_set<std::int64_t> wanted(slamIds.begin(), slamIds.end());
  std::vector<Vec2> uv;
  std::vector<std::int64_t> of;
  for (const auto& f : m_slam->features())
  {
    Vec2 p;
    if (!wanted.count(f.id) || !pixelOf(f, p)) continue;
    uv.push_back(p);
    of.push_back(f.id);
  }
  const auto ids = m_shadow->addFeatures(grey, uv);
  m_shadow->setMapCopies(ids, true);
  for (std::size_t k = 0; k < ids.size(); ++k)
    if (ids[k] >= 0) m_probation[ids[k]] = of[k];
}

void CMonoSlamSystem::settleProbation(const shadow::TShadowReport& srep, std::vector<shadow::TPromotion>& promotions)
{
  const auto slamFeature = [this](std::int64_t id) -> const slam::TFeature* {
    for (const auto& f : m_slam->features())
      if (f.id == id) return &f;
    return nullptr;
  };
  // A copy decided static: its SLAM feature stays (the copy is not promoted twice).
  std::vector<shadow::TPromotion> kept;
  for (const auto& p : promotions)
  {
    const auto it = m_probation.find(p.id);
    if (it == m_probation.end() || !slamFeature(it->second))
      kept.push_back(p);  // (a copy whose feature SLAM deleted meanwhile enters as any promotion)
    if (it != m_probation.end()) m_probation.erase(it);
  }
  promotions = std::move(kept);
  // Decided dynamic: a copy's SLAM feature leaves the map; the track starts with its mapped past.
  std::vector<std::int64_t> movers;
  for (const auto& d : srep.decisions)
  {
    if (d.cls != shadow::EShadowClass::Dynamic) continue;
    if (const auto it = m_probation.find(d.id); it != m_probation.end())
    {
      // (A feature SLAM uses in this very frame stays: its own rejections will hand it over if it moves;
      // a map is never emptied by its copies' decisions.)
      const slam::TFeature* f = slamFeature(it->second);
      if (f && f->tLastInlier != srep.timestamp)
      {
        const auto rows = mappedPast(*f, d.id);
        m_frame.mappedPast.insert(m_frame.mappedPast.end(), rows.begin(), rows.end());
        movers.push_back(f->id);
      }
      m_probation.erase(it);
    }
    else if (const auto p = m_pastOf.find(d.id); p != m_pastOf.end())
    {
      m_frame.mappedPast.insert(m_frame.mappedPast.end(), p->second.begin(), p->second.end());
      m_pastOf.erase(p);
    }
  }
  if (!movers.empty()) m_slam->removeFeatures(movers);
  m_frame.firstMapMovers = static_cast<int>(movers.size());
  // Probation lasts while the bank says the camera does not translate: then the depth-free test
  // decides, with full power and no false dynamics from an over-confident translation (the three-ray
  // test's, doc/shadow.md); a translating camera's first-map movers are left to RANSAC and the handover.
  if (!m_probation.empty() && notTranslatingProbability() < 0.5)
  {
    std::vector<std::int64_t> copies;
    for (const auto& c : m_probation) copies.push_back(c.first);
    m_shadow->removeFeatures(copies);
    m_probation.clear();
  }
  // Forget the copies and pasts of features that left the shadow filter (lost, timed out, promoted).
  if (m_probation.empty() && m_pastOf.empty()) return;
  std::unordered_set<std::int64_t> held;
  for (const auto& f : m_shadow->features())
    if (f.cls == shadow::EShadowClass::Pending) held.insert(f.id);
  for (auto it = m_probation.begin(); it != m_probation.end();) it = held.count(it->first) ? std::next(it) : m_probation.erase(it);
  for (auto it = m_pastOf.begin(); it != m_pastOf.end();) it = held.count(it->first) ? std::next(it) : m_pastOf.erase(it);
}

std::vector<TMappedPast> CMonoSlamSystem::mappedPast(const slam::TFeature& f, std::int64_t trackId) const
{
  const auto est = m_slam->featureWorldEstimate(f);
  const auto rangeAt = [&](double t, const Vec3& fallback) {
    Vec3 c = fallback;
    double best = std::numeric_limits<double>::infinity();
    for (const auto& [ts, r] : m_cameraPath)
      if (std::abs(ts - t) < best) best = std::abs(ts - t), c = r;
    return (est.p_W - c).norm();
  };
  double rel = 0;
  const double d = (est.p_W - m_slam->cameraPosition()).norm();
  if (est.inverseDepth)
    rel = std::sqrt(std::max(est.cov_tpr(2, 2), 0.0)) / std::max(est.rho, 1e-3);
  else if (d > 0)
  {
    const Vec3 u = (est.p_W - m_slam->cameraPosition()) / d;
    rel = std::sqrt(std::max(double(u.transpose() * est.cov_W * u), 0.0)) / d;
  }
  std::vector<TMappedPast> rows;
  TMappedPast first;
  first.id = trackId;
  first.timestamp = f.tInit;
  first.p_W = est.p_W;
  first.range = (est.p_W - f.r0).norm();
  first.rangeRelSigma = rel;
  // Its first pixel: the point seen from the camera of its first observation.
  if (!m_slam->camera().project(math::quatRotate(math::quatConjugate(f.q0), est.p_W - f.r0), first.uv)) return rows;
  rows.push_back(first);
  if (f.nMatched > 0 && f.tLastInlier > f.tInit)
  {
    TMappedPast last = first;
    last.timestamp = f.tLastInlier;
    last.uv = f.uvLastInlier;
    last.range = rangeAt(f.tLastInlier, m_slam->cameraPosition());
    rows.push_back(last);
  }
  return rows;
}
}  // namespace immslam::system
