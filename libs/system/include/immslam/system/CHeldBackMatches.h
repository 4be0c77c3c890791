/* imm-monoslam — the shadow filter's matches of the features it holds back, for the bundle
 * adjustments behind the filter (the online keyframe smoother, the whole-run refinement). */
#pragma once

#include <immslam/math/types.h>
#include <immslam/shadow/shadow_types.h>
#include <immslam/tracking/CMonoSlamIMM.h>

#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

namespace immslam::system
{
/** A new feature spends its first frames in the shadow filter (MonoSLAMBOT), measured but not in
 * SLAM's update: what the SLAM filter lacks while it waits, a bundle adjustment behind the filter
 * can have afterwards. This class keeps a pending feature's matches until the feature is known to
 * be static, then hands them over:
 * - a feature SLAM took (promoted after a static decision, or released undecided): once SLAM has
 *   used it in kConfirmUpdates updates. SLAM's active search and 1-point RANSAC test it against the
 *   map and the camera with its own prior, and a track that is no fixed point (a corner sliding
 *   along an edge, a T-junction) is rejected and deleted before, its held matches with it;
 * - a watched feature decided static (retired: SLAM never takes it): at its decision.
 * A feature decided dynamic, seen moving (held without a decision), lost or timed out takes its
 * matches with it. A first map's probation copy shares its id with the SLAM feature, which SLAM
 * measures itself: it is never held. Ids are the system's (unique across both filters). */
class CHeldBackMatches
{
 public:
  static constexpr int kConfirmUpdates = 5;

  /** One measurement of a past frame. */
  struct TMatch
  {
    std::size_t frame = 0;    ///< index of the frame (0 = the run's first)
    std::int64_t id = 0;      ///< the feature's id (the one SLAM goes on measuring it with)
    Vec2 uv = Vec2::Zero();   ///< the measured pixel (distorted, as the matcher found it)
  };

  /** One frame, after the system processed it.
   * \param frame its index (0 = the first, one call per frame, in order)
   * \param srep the shadow filter's report of the frame, or null (none in this frame)
   * \param inSlam the ids of SLAM's features after the frame (promotions and releases included)
   * \param slamUsed the ids SLAM used in its update of this frame (its inliers)
   * \return the matches that became usable with this frame: every frame of each such feature's
   *         time in the shadow filter. */
  std::vector<TMatch> update(std::size_t frame, const shadow::TShadowReport* srep,
                             const std::unordered_set<std::int64_t>& inSlam,
                             const std::unordered_set<std::int64_t>& slamUsed);

  /** The same, with SLAM's features and the inliers of its last report (`slam`: the filter after
   * the frame). */
  std::vector<TMatch> update(std::size_t frame, const shadow::TShadowReport* srep, const slam::CMonoSlamIMM& slam);

  /** Features whose matches are held now (pending, or in SLAM and not yet confirmed). */
  std::size_t held() const { return m_held.size() + m_confirming.size(); }

 private:
  std::unordered_map<std::int64_t, std::vector<TMatch>> m_held;  ///< per pending feature
  /** Per feature SLAM took: its updates since, and its held matches. */
  std::unordered_map<std::int64_t, std::pair<int, std::vector<TMatch>>> m_confirming;
};
}  // namespace immslam::system
