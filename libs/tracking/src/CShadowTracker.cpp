/* imm-monoslam — the shadow filter's image side: patches and the active search. */
#include <immslam/math/chi2.h>
#include <immslam/tracking/CShadowTracker.h>

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <string>
#include <unordered_set>

namespace immslam::shadow
{
namespace
{
double msSince(std::chrono::steady_clock::time_point t0)
{
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

CShadowTracker::CShadowTracker(const CShadowFilter::TOptions& opts, camera::CCameraModel::Ptr cam,
                               CShadowFilter::IdAllocator ids)
    : m_filter(opts, std::move(cam), std::move(ids))
{
  const auto& o = m_filter.options();
  m_search.gateChi2 = math::chi2Quantile(o.search_probability, 2);
  m_search.minScore = o.min_ncc;
  m_search.maxHalfExtentPx = o.max_search_half_extent_px;
}

const frontend::CFeaturePatch* CShadowTracker::patchOf(std::int64_t id) const
{
  const auto it = m_patches.find(id);
  return it == m_patches.end() ? nullptr : &it->second;
}

std::vector<std::int64_t> CShadowTracker::addFeatures(const cv::Mat& grey, const std::vector<Vec2>& uv)
{
  const auto& cam = m_filter.camera();
  if (!grey.empty() && (grey.type() != CV_8UC1 || grey.cols != cam.width() || grey.rows != cam.height()))
    throw std::runtime_error("shadow::CShadowTracker::addFeatures: expected a CV_8UC1 image of the camera's size");
  std::vector<std::int64_t> ids;
  ids.reserve(uv.size());
  for (const Vec2& p : uv)
  {
    // The filter refuses first (max_features, not finite); then a patch that does not fit.
    frontend::CFeaturePatch patch;
    const bool refused = m_filter.size() >= static_cast<std::size_t>(m_filter.options().max_features) || !p.allFinite();
    if (refused || (!grey.empty() && !patch.extract(grey, p, m_filter.options().patch_half_size)))
    {
      ids.push_back(-1);
      continue;
    }
    const std::int64_t id = m_filter.addFeatures({p}).front();
    if (id >= 0 && patch.valid()) m_patches.emplace(id, std::move(patch));
    ids.push_back(id);
  }
  return ids;
}

std::vector<TShadowMatch> CShadowTracker::searchAll(const cv::Mat& grey, const cv::Mat& excluded)
{
  const auto& o = m_filter.options();
  const auto& cam = m_filter.camera();
  std::vector<TShadowMatch> matches;
  for (const auto& f : m_filter.features())
  {
    const frontend::CFeaturePatch* patch = patchOf(f.id);
    if (!patch || !f.predicted.allFinite() || !cam.isInImage(f.predicted, o.patch_half_size + 1)) continue;
    // Predicted appearance: the plane facing the first camera through the current estimate, in C0.
    Mat2 A = Mat2::Identity();
    if (o.warp_patches)
    {
      TShadowState s = f.ekf;
      s.x[kW] = std::max(s.x[kW], 0.01);
      const Vec3 p_C0 = f.track.T_0k.transform(shadowPosition(s));
      A = frontend::patchWarp(cam, Vec3::Zero(), Vec4(1, 0, 0, 0), f.track.T_0k.t, f.track.T_0k.q, p_C0, Vec3::Zero());
    }
    patch->predictTemplate(A, m_templ);
    const frontend::TSearchResult res = frontend::searchInEllipse(grey, m_templ, f.predicted, f.S, m_search, m_ws);
    matches.push_back({f.id, res.found && !frontend::maskedAt(excluded, res.uv), res.uv, res.score});
  }
  return matches;
}

void CShadowTracker::forgetDropped()
{
  std::unordered_set<std::int64_t> held;
  for (const auto& f : m_filter.features()) held.insert(f.id);
  for (auto it = m_patches.begin(); it != m_patches.end();)
    it = held.count(it->first) ? std::next(it) : m_patches.erase(it);
}

const TShadowReport& CShadowTracker::processFrame(const TCameraMotion& motion, const cv::Mat& grey,
                                                  const cv::Mat& excluded)
{
  const auto& cam = m_filter.camera();
  if (grey.empty() || grey.type() != CV_8UC1 || grey.cols != cam.width() || grey.rows != cam.height())
    throw std::runtime_error("shadow::CShadowTracker::processFrame: expected a CV_8UC1 image of the camera's size "
                             "at frame " + std::to_string(motion.frame));
  if (!excluded.empty() && (excluded.type() != CV_8UC1 || excluded.size() != grey.size()))
    throw std::runtime_error("shadow::CShadowTracker::processFrame: the exclusion mask must be empty or CV_8UC1 of "
                             "the image's size at frame " + std::to_string(motion.frame));
  m_filter.predict(motion);
  const auto t0 = std::chrono::steady_clock::now();
  const auto matches = searchAll(grey, frontend::growExclusion(excluded, m_filter.options().patch_half_size));
  const double searchMs = msSince(t0);
  m_filter.update(matches);
  const TShadowReport& rep = m_filter.finishFrame(searchMs);
  forgetDropped();
  return rep;
}

const TShadowReport& CShadowTracker::processMeasurements(const TCameraMotion& motion,
                                                         const std::vector<std::pair<std::int64_t, Vec2>>& z)
{
  const TShadowReport& rep = m_filter.processMeasurements(motion, z);
  forgetDropped();
  return rep;
}

std::vector<TPromotion> CShadowTracker::releaseUnresolved(int maxCount, int minMeasured,
                                                          const std::unordered_set<std::int64_t>& notReleased)
{
  auto out = m_filter.releaseUnresolved(maxCount, minMeasured, notReleased);
  forgetDropped();
  return out;
}

void CShadowTracker::removeFeatures(const std::vector<std::int64_t>& ids)
{
  m_filter.removeFeatures(ids);
  forgetDropped();
}
}  // namespace immslam::shadow
