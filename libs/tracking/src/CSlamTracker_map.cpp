/* imm-monoslam — the SLAM tracker's map policy: new features with their templates, the bounded map,
 * the deletion rule and the inverse depth -> XYZ conversion (paper Sec. IV-2), carried out by the
 * filter on every mode. */
#include <immslam/tracking/CSlamTracker.h>

#include <algorithm>
#include <unordered_set>

namespace immslam::slam
{
CImmSlamFilter::TOptions CSlamTracker::TOptions::filterOptions() const
{
  CImmSlamFilter::TOptions o;
  o.sigma_pixel = sigma_pixel;
  o.adaptive_pixel_noise = adaptive_pixel_noise;
  o.adaptive_motion_noise = adaptive_motion_noise;
  o.adaptive_shake = adaptive_shake;
  o.adaptive_noise_rate = adaptive_noise_rate;
  o.min_sigma_pixel = min_sigma_pixel;
  o.max_sigma_pixel = max_sigma_pixel;
  o.init_rho = init_rho;
  o.init_rho_std = init_rho_std;
  o.init_linear_velocity_std_px = init_linear_velocity_std_px;
  o.init_angular_velocity_std_px = init_angular_velocity_std_px;
  o.frame_rate_hz = frame_rate_hz;
  o.num_threads = num_threads;
  return o;
}

void CSlamTracker::manageMap(bool allowDeletion)
{
  const auto& features = m_filter.features();
  // 1. Deletion (MonoSLAM rule, paper ref. [6]): searched often, matched rarely.
  std::vector<char> drop(features.size(), 0);
  std::vector<std::int64_t> dropped;
  for (std::size_t k = 0; k < features.size() && allowDeletion; ++k)
  {
    const auto& f = features[k];
    if (f.nPredicted >= m_opts.delete_min_predictions && f.nMatched < m_opts.delete_min_match_ratio * f.nPredicted)
    {
      drop[k] = 1;
      dropped.push_back(f.id);
    }
  }
  // 2. Inverse depth -> XYZ when the linearity index is small (paper ref. [3]).
  std::vector<char> convert(features.size(), 0);
  if (m_opts.convert_to_xyz)
    for (std::size_t k = 0; k < features.size(); ++k)
      if (!drop[k] && features[k].kind == EFeatureKind::InverseDepth &&
          m_filter.linearityIndex(features[k]) < m_opts.linearity_threshold)
        convert[k] = 1;
  m_report.nDeleted = static_cast<int>(dropped.size());
  m_report.nConverted = static_cast<int>(std::count(convert.begin(), convert.end(), 1));
  if (!m_report.nDeleted && !m_report.nConverted) return;
  m_filter.reparametrizeMap(drop, convert);
  for (const auto id : dropped) m_patches.erase(id);
}

void CSlamTracker::removeFeatures(const std::vector<std::int64_t>& ids)
{
  m_filter.removeFeatures(ids);
  for (const auto id : ids) m_patches.erase(id);
}

void CSlamTracker::evictForRoom(int incoming)
{
  const int room = m_opts.max_map_features - static_cast<int>(m_filter.features().size());
  if (room >= incoming) return;
  std::vector<std::pair<std::int64_t, std::int64_t>> byAge;  // (lastSeenFrame, id)
  for (const auto& f : m_filter.features())
    if (f.lastSeenFrame < m_filter.frame()) byAge.emplace_back(f.lastSeenFrame, f.id);
  std::sort(byAge.begin(), byAge.end());
  std::vector<std::int64_t> evict;
  for (std::size_t i = 0; i < byAge.size() && static_cast<int>(evict.size()) < incoming - room; ++i)
    evict.push_back(byAge[i].second);
  removeFeatures(evict);
}

std::vector<std::int64_t> CSlamTracker::addFeaturesAt(const cv::Mat& grey, const std::vector<Vec2>& uvs,
                                                      const std::vector<std::pair<double, double>>& rhoPrior,
                                                      const std::vector<std::int64_t>& givenIds)
{
  std::vector<std::int64_t> ids(uvs.size(), -1);
  // Bounded map: evict the features unseen for longest (not visible now) to make room.
  evictForRoom(static_cast<int>(uvs.size()));
  const int capacity = m_opts.max_map_features - static_cast<int>(m_filter.features().size());
  std::vector<CImmSlamFilter::TNewFeature> fresh;
  std::vector<frontend::CFeaturePatch> patches;
  for (std::size_t i = 0; i < uvs.size() && static_cast<int>(fresh.size()) < capacity; ++i)
  {
    frontend::CFeaturePatch patch;
    if (!grey.empty() && !patch.extract(grey, uvs[i], m_opts.patch_half_size)) continue;
    CImmSlamFilter::TNewFeature nf;
    nf.uv = uvs[i];
    nf.rho = i < rhoPrior.size() ? rhoPrior[i].first : m_opts.init_rho;
    nf.sigmaRho = i < rhoPrior.size() ? rhoPrior[i].second : m_opts.init_rho_std;
    nf.id = i < givenIds.size() ? givenIds[i] : m_filter.allocateId();
    ids[i] = nf.id;
    fresh.push_back(nf);
    patches.push_back(std::move(patch));
  }
  m_filter.addFeatures(fresh);
  for (std::size_t a = 0; a < fresh.size(); ++a)
  {
    // (An id may come back, e.g. a feature handed over to the shadow filter and promoted again.)
    if (patches[a].valid())
      m_patches[fresh[a].id] = std::move(patches[a]);
    else
      m_patches.erase(fresh[a].id);
  }
  m_report.nAdded += static_cast<int>(fresh.size());
  return ids;
}
}  // namespace immslam::slam
