/* imm-monoslam — the image side of the MonoSLAMBOT shadow filter (Migliore et al., ../shared/papers/
 * monoslambot-shadow-filter.md, Sec. III): each held feature's appearance (its patch at the first
 * observation) and its active search in the image inside the filter's 95 % innovation ellipse, the
 * patch warped to the predicted appearance (frontend::searchInEllipse, frontend::patchWarp).
 *
 * Roles as in CSlamTracker: the estimator (CShadowFilter) predicts, updates with given associations
 * and classifies, and knows no image; this class associates. Per frame (processFrame):
 * filter.predict(); the search of every feature with a patch; filter.update(matches);
 * filter.finishFrame(). Known data association (processMeasurements) is the same "associate, then
 * update" flow with the matches given. Namespace shadow: the shadow filter's family; library
 * tracking: the image work. No file output and no GUI. */
#pragma once

#include <immslam/camera/CCameraModel.h>
#include <immslam/frontend/frontend.h>
#include <immslam/shadow/CShadowFilter.h>

#include <opencv2/core/mat.hpp>

#include <cstdint>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

namespace immslam::shadow
{
class CShadowTracker
{
 public:
  /** \param opts [shadow] options (the filter's, its search block included). \param ids optional id
   * allocator (CShadowFilter). \throws std::runtime_error on a null camera or invalid options. */
  CShadowTracker(const CShadowFilter::TOptions& opts, camera::CCameraModel::Ptr cam,
                 CShadowFilter::IdAllocator ids = {});

  /** One frame with images: prediction (eq. 2), active search of every feature with a patch in its
   * innovation ellipse, update (eqs. 3-5), classification (Sec. III-A), drops. \param grey CV_8UC1,
   * the camera's size. \param excluded optional CV_8UC1 mask of the same size, non-zero where no
   * match is accepted (within patch_half_size; CSlamTracker::setExclusionMask). The report stays
   * valid until the next call. \throws std::runtime_error on an image or mask of another type or size. */
  const TShadowReport& processFrame(const TCameraMotion& motion, const cv::Mat& grey,
                                    const cv::Mat& excluded = cv::Mat());
  /** The same step with known data association and no image (CShadowFilter::processMeasurements). */
  const TShadowReport& processMeasurements(const TCameraMotion& motion,
                                           const std::vector<std::pair<std::int64_t, Vec2>>& z);

  /** New features observed at pixels uv of the frame just processed (CShadowFilter::addFeatures).
   * With a non-empty grey their patches are extracted there (-1 returned where it does not fit); an
   * empty grey stores no patch (processMeasurements only). Returns the ids (-1: refused). */
  std::vector<std::int64_t> addFeatures(const cv::Mat& grey, const std::vector<Vec2>& uv);

  /** Pending features released into SLAM (CShadowFilter::releaseUnresolved). */
  std::vector<TPromotion> releaseUnresolved(int maxCount, int minMeasured,
                                            const std::unordered_set<std::int64_t>& notReleased = {});
  /** Removes features by id (CShadowFilter::removeFeatures). */
  void removeFeatures(const std::vector<std::int64_t>& ids);
  /** Marks copies of SLAM map features, or no longer (CShadowFilter::setMapCopies). */
  void setMapCopies(const std::vector<std::int64_t>& ids, bool copies) { m_filter.setMapCopies(ids, copies); }
  /** Measured or predicted pixels of all held features (to keep new detections away). */
  std::vector<Vec2> occupiedPixels() const { return m_filter.occupiedPixels(); }
  /** The held features (read-only). */
  const std::vector<TShadowFeature>& features() const { return m_filter.features(); }
  std::size_t size() const { return m_filter.size(); }
  /** The stored patch of a feature (nullptr: none, e.g. added without an image). */
  const frontend::CFeaturePatch* patchOf(std::int64_t id) const;
  /** The estimator. */
  const CShadowFilter& filter() const { return m_filter; }
  /** The SLAM map's inliers of frame `frame`, before that frame (CShadowFilter::observeMap). */
  void observeMap(std::int64_t frame, std::vector<std::pair<std::int64_t, Vec2>> z) { m_filter.observeMap(frame, std::move(z)); }
  const TShadowReport& lastReport() const { return m_filter.lastReport(); }

 private:
  /** The active search of every predicted feature with a patch; the associations for the filter. */
  std::vector<TShadowMatch> searchAll(const cv::Mat& grey, const cv::Mat& excluded);
  /** Forgets the patches of features that left the filter. */
  void forgetDropped();

  CShadowFilter m_filter;
  std::unordered_map<std::int64_t, frontend::CFeaturePatch> m_patches;  ///< appearance of the features, by id
  frontend::TSearchParams m_search;
  frontend::TSearchWorkspace m_ws;
  cv::Mat m_templ;
};
}  // namespace immslam::shadow
