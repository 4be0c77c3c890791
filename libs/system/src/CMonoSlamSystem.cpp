/* imm-monoslam — wiring of the SLAM filter and the shadow filter per frame (MonoSLAMBOT Fig. 1). */
#include <immslam/core/config.h>
#include <immslam/math/quaternion.h>
#include <immslam/system/CMonoSlamSystem.h>

#include <algorithm>
#include <chrono>
#include <limits>
#include <stdexcept>
#include <string>
#include <unordered_set>

namespace immslam::system
{
namespace
{
using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }
/** Features that addFeaturesAt() did add (ids >= 0; -1 where the patch did not fit). */
int countAdded(const std::vector<std::int64_t>& ids)
{
  return static_cast<int>(std::count_if(ids.begin(), ids.end(), [](std::int64_t id) { return id >= 0; }));
}
/** The SLAM filter's inliers of a frame (id, measured pixel): points the static world's consensus holds. */
std::vector<std::pair<std::int64_t, Vec2>> mapInliers(const slam::TFrameReport& rep)
{
  std::vector<std::pair<std::int64_t, Vec2>> z;
  for (const auto& s : rep.searches)
    if (s.status == slam::TSearchRecord::EStatus::LowInnovationInlier ||
        s.status == slam::TSearchRecord::EStatus::RescuedInlier)
      z.emplace_back(s.id, s.z);
  return z;
}
/** Memory of the automatic pending weight: outcome counts decay by this factor per frame (~100 frames). */
constexpr double kOutcomeDecay = 0.99;
/** The new tracks `fresh` farthest from every feature held (`avoid`), one at a time (as corners
 * in empty cells), at most `want`: their track ids and pixels. */
void farthestTracks(const std::vector<std::pair<std::int64_t, Vec2>>& fresh, const std::vector<Vec2>& avoid, int want,
                    std::vector<std::int64_t>& tracks, std::vector<Vec2>& uv)
{
  std::vector<double> gap(fresh.size(), std::numeric_limits<double>::infinity());
  for (std::size_t k = 0; k < fresh.size(); ++k)
    for (const auto& a : avoid) gap[k] = std::min(gap[k], (fresh[k].second - a).norm());
  while (static_cast<int>(uv.size()) < want)
  {
    const auto best = std::max_element(gap.begin(), gap.end()) - gap.begin();
    if (gap[best] < 0) break;  // every new track taken
    tracks.push_back(fresh[best].first);
    uv.push_back(fresh[best].second);
    gap[best] = -1;
    for (std::size_t k = 0; k < fresh.size(); ++k)
      if (gap[k] >= 0) gap[k] = std::min(gap[k], (fresh[k].second - uv.back()).norm());
  }
}
}  // namespace

double CMonoSlamSystem::TOptions::parsePendingWeight(const std::string& text, const std::string& section)
{
  if (text == "auto") return -1.0;
  std::size_t used = 0;
  double w = std::numeric_limits<double>::quiet_NaN();
  try
  {
    w = std::stod(text, &used);
  }
  catch (const std::exception&)
  {
    used = 0;
  }
  if (used != text.size() || !(w >= 0 && w <= 1))
    throw std::runtime_error("[" + section + "] pending_weight = '" + text + "': expected a number in [0, 1] or 'auto'");
  return w;
}

void CMonoSlamSystem::TSearchOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
  IMMSLAM_LOAD_INT(patch_half_size);
  IMMSLAM_LOAD_BOOL(warp_patches);
  IMMSLAM_LOAD_DOUBLE(min_ncc);
  IMMSLAM_LOAD_DOUBLE(search_probability);
  IMMSLAM_LOAD_DOUBLE(max_search_half_extent_px);
  core::requireInRange(patch_half_size, 2, 15, s, "patch_half_size");
  core::requireInRange(min_ncc, -1, 1, s, "min_ncc");
  core::requireInRange(search_probability, 0.5, 0.99999, s, "search_probability");
  core::requirePositive(max_search_half_extent_px, s, "max_search_half_extent_px");
}

void CMonoSlamSystem::TSearchOptions::saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const
{
  MRPT_SAVE_CONFIG_VAR_COMMENT(patch_half_size, "template half size of both filters (5 -> 11x11 px)");
  MRPT_SAVE_CONFIG_VAR_COMMENT(warp_patches, "predict patch appearance by an affine warp");
  MRPT_SAVE_CONFIG_VAR_COMMENT(min_ncc, "minimum zero-mean NCC of a match");
  MRPT_SAVE_CONFIG_VAR_COMMENT(search_probability, "probability of the search ellipse (2 dof)");
  MRPT_SAVE_CONFIG_VAR_COMMENT(max_search_half_extent_px, "clip of very large search regions (px)");
}

void CMonoSlamSystem::TSearchOptions::applyTo(slam::CMonoSlamIMM::TOptions& so, shadow::CShadowFilter::TOptions& sh) const
{
  so.patch_half_size = sh.patch_half_size = patch_half_size;
  so.warp_patches = sh.warp_patches = warp_patches;
  so.min_ncc = sh.min_ncc = min_ncc;
  so.search_probability = sh.search_probability = search_probability;
  so.max_search_half_extent_px = sh.max_search_half_extent_px = max_search_half_extent_px;
  sh.sigma_pixel = so.sigma_pixel;
  sh.init_rho = so.init_rho;
  sh.init_rho_std = so.init_rho_std;
}

const std::map<std::string, std::string>& CMonoSlamSystem::removedKeys()
{
  static const std::map<std::string, std::string> removed = [] {
    std::map<std::string, std::string> m;
    for (const char* k : {"patch_half_size", "warp_patches", "min_ncc", "search_probability", "max_search_half_extent_px"})
    {
      m[std::string("[slam] ") + k] = std::string("moved to [search] ") + k + " (one search for both filters)";
      m[std::string("[shadow] ") + k] = std::string("moved to [search] ") + k + " (one search for both filters)";
    }
    for (const char* k : {"sigma_pixel", "init_rho", "init_rho_std"})
      m[std::string("[shadow] ") + k] = std::string("removed: both filters use [slam] ") + k;
    m["[imm] general_entry"] =
        "removed: the default Markov matrix never switches a still or rotating mode into a general one "
        "(the former 'evidence'; doc/imm.md); give any other matrix with [imm] transition_matrix";
    m["[imm] lazy_prediction"] = "removed: dormant modes are always predicted lazily (it is exact)";
    m["[shadow] static_power_worst_case"] =
        "removed: the static power is the average over directions (the former 'false'; doc/shadow.md)";
    m["[shadow] increment_cov_scale"] = "removed: the SLAM increments' covariance is used as it is";
    m["[shadow] ekf_iterations"] = "removed: the shadow filter makes one EKF update per frame";
    m["[shadow] id_offset"] = "removed: the system numbers the features of both filters";
    m["[shadow] min_inverse_distance"] = "removed: a fixed clamp (1e-3) places tracks at infinity";
    // Tuning internals nobody outside the algorithm turns: constants at their former defaults (the k*
    // constants beside the option fields).
    const auto internal = [&m](const std::string& key, const std::string& what) {
      m[key] = "removed: internal constant (" + what + ")";
    };
    internal("[slam] adaptive_noise_rate", "0.05; doc/estimator.md");
    internal("[slam] min_sigma_pixel", "0.25 px; [slam] max_sigma_pixel remains");
    internal("[slam] init_linear_velocity_std_px", "5 px/frame; doc/estimator.md");
    internal("[slam] init_angular_velocity_std_px", "5 px/frame; doc/estimator.md");
    internal("[slam] expand_search_factor", "2; doc/estimator.md");
    internal("[slam] expand_below_fraction", "0.5; doc/estimator.md");
    internal("[slam] min_corner_distance_px", "12 px; doc/estimator.md");
    internal("[slam] border_px", "10 px; doc/estimator.md");
    internal("[slam] min_shi_tomasi", "0.01; doc/estimator.md");
    internal("[slam] delete_min_predictions", "10, MonoSLAM's deletion rule; doc/estimator.md");
    internal("[slam] delete_min_match_ratio", "0.5, MonoSLAM's deletion rule; doc/estimator.md");
    internal("[slam] linearity_threshold", "0.1; doc/estimator.md");
    internal("[slam] relocalise_min_inliers", "8; doc/estimator.md, Relocalisation");
    internal("[slam] relocalise_max_frames", "90; doc/estimator.md, Relocalisation");
    internal("[slam] relocalise_patience", "5; doc/estimator.md, Relocalisation");
    internal("[slam] relocalise_after_gap", "10 frame periods; doc/estimator.md, Relocalisation");
    m["[imm] transition_stay"] = "removed: the default Markov matrix has 0.995 on the diagonal (doc/imm.md); give any "
                                 "other matrix with [imm] transition_matrix";
    internal("[imm] probability_floor", "1e-4; doc/imm.md");
    internal("[ransac] success_probability", "0.99; doc/estimator.md, 1-point RANSAC");
    internal("[ransac] max_hypotheses", "200; doc/estimator.md, 1-point RANSAC");
    internal("[ransac] rescue_probability", "0.99; doc/estimator.md, 1-point RANSAC");
    internal("[shadow] init_velocity_std_px", "5 px/frame; doc/shadow.md");
    const std::pair<const char*, const char*> shadowInternals[] = {
        {"alpha", "0.05"}, {"min_test_frames", "3"}, {"dynamic_rejections", "5"}, {"dynamic_window", "5"},
        {"static_acceptances", "5"}, {"static_min_frames", "10"}, {"static_min_velocity_px", "1 px/frame"},
        {"static_power", "0.95"}, {"max_pending_frames", "150"}, {"max_missed_frames", "5"},
        {"dynamic_max_missed_frames", "10"}};
    for (const auto& [k, v] : shadowInternals)
      internal(std::string("[shadow] ") + k, std::string(v) + "; doc/shadow.md");
    m["[output] plots"] =
        "removed: the run writes no pictures of its series; share/scripts/plot-run.py RUN_DIR draws them from "
        "the run's CSV files";
    return m;
  }();
  return removed;
}

void CMonoSlamSystem::TOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
  IMMSLAM_LOAD_BOOL(shadow_filter);
  IMMSLAM_LOAD_INT(handover_rejections);
  IMMSLAM_LOAD_INT(starved_below);
  IMMSLAM_LOAD_INT(release_min_measured);
  IMMSLAM_LOAD_STRING(pending_weight);
  IMMSLAM_LOAD_INT(watch_features);
  parsePendingWeight(pending_weight, s);
  core::requireInRange(watch_features, 0, 1000, s, "watch_features");
  core::requireNonNegative(handover_rejections, s, "handover_rejections");
  core::requireNonNegative(starved_below, s, "starved_below");
  core::requirePositive(release_min_measured, s, "release_min_measured");
}

void CMonoSlamSystem::TOptions::saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const
{
  MRPT_SAVE_CONFIG_VAR_COMMENT(shadow_filter, "new features go first to the MonoSLAMBOT shadow filter");
  MRPT_SAVE_CONFIG_VAR_COMMENT(handover_rejections,
                               "SLAM features rejected this many frames in a row go back to the shadow filter (0: never)");
  MRPT_SAVE_CONFIG_VAR_COMMENT(starved_below,
                               "SLAM short of features (fewer in view): release unresolved shadow features (0: never)");
  MRPT_SAVE_CONFIG_VAR_COMMENT(release_min_measured, "frames a shadow feature must be tracked to be released");
  MRPT_SAVE_CONFIG_VAR_COMMENT(pending_weight, "weight of a pending shadow feature in the count of features in view, in [0, 1], or auto (the recent fraction of pending features that ended in SLAM)");
  MRPT_SAVE_CONFIG_VAR_COMMENT(watch_features, "pending shadow features kept in view even when SLAM needs none, to see what moves (0: only when SLAM needs features)");
}

CMonoSlamSystem::CMonoSlamSystem(const mrpt::config::CConfigFileBase& cfg, camera::CCameraModel::Ptr cam)
{
  m_opts.loadFromConfigFile(cfg, "system");
  m_searchOpts.loadFromConfigFile(cfg, "search");
  m_slamOpts.loadFromConfigFile(cfg, "slam");
  m_bankOpts.loadFromConfigFile(cfg, "imm");
  m_ransacOpts.loadFromConfigFile(cfg, "ransac");
  m_shadowOpts.loadFromConfigFile(cfg, "shadow");
  m_searchOpts.applyTo(m_slamOpts, m_shadowOpts);
  // The power of a static decision is averaged over directions, not required in every one (the shadow
  // filter's own default): a slow mover along its own viewing ray that gets promoted is caught by SLAM's
  // outlier rejection when it moves across and handed back (handover_rejections; doc/shadow.md).
  m_shadowOpts.static_power_worst_case = false;
  m_pendingWeight = TOptions::parsePendingWeight(m_opts.pending_weight, "system");
  m_slam = std::make_unique<slam::CMonoSlamIMM>(m_slamOpts, m_bankOpts, m_ransacOpts, cam);
  if (m_opts.shadow_filter)
    m_shadow = std::make_unique<shadow::CShadowTracker>(m_shadowOpts, cam, [this] { return m_slam->allocateId(); });
}

CMonoSlamSystem::~CMonoSlamSystem() = default;

shadow::TCameraMotion CMonoSlamSystem::cameraMotion(double timestamp, double dt) const
{
  // The SLAM camera pose and its motion since the previous frame, with covariances.
  const Vec3 r = m_slam->cameraPosition();
  const Vec4 q = m_slam->cameraOrientation();
  shadow::TCameraMotion m = shadow::TCameraMotion::FromPoses(m_prevR, m_prevQ, r, q);
  m.timestamp = timestamp;
  m.frame = m_slam->lastReport().frame;
  m.dt = dt;
  // Pose covariance in [dr; dtheta] with R = R_est Exp(dtheta): dtheta = 2 vec(conj(q_est) (x) q).
  Mat4 L;
  math::quatMultiply(math::quatConjugate(q), q, nullptr, &L);
  Eigen::Matrix<double, 6, 7> J = Eigen::Matrix<double, 6, 7>::Zero();
  J.topLeftCorner<3, 3>().setIdentity();
  J.bottomRightCorner<3, 4>() = 2.0 * L.bottomRows<3>();
  m.cov_W_C = J * m_slam->cameraPoseCovariance() * J.transpose();
  // Increment covariance from the velocities' (t = v dt, dtheta = w dt, first order).
  m.cov_increment = m_slam->velocityCovariance() * dt * dt;
  m.pNotTranslating = notTranslatingProbability();
  // Lost (the pose is a prediction) or relocalised (the increment holds the jump): no measured motion.
  m.measured = !m_slam->lostThisFrame() && !m_slam->lastReport().relocalised;
  return m;
}

int CMonoSlamSystem::promoteFromShadow(const shadow::TShadowReport& srep, const cv::Mat& grey, bool holding,
                                        int slamInView)
{
  // Promotions into SLAM keep their ids and the shadow's inverse-depth estimate as the prior.
  std::vector<shadow::TPromotion> promotions = srep.promotions;
  settleProbation(srep, promotions);
  if (holding) promotions.clear();
  retireWatched(promotions);
  // Without parallax nothing can be classified. While the IMM says the camera is not translating
  // (stationary and rotation families dominate), the SLAM takes the unresolved features it needs,
  // as the IMM paper's filter does with inverse depth; with translation, only when starving.
  const int inView = slamInView + static_cast<int>(promotions.size());
  double pGeneral = 0;
  const VecX mu = m_slam->modelProbabilities();
  for (int i = 0; i < mu.size(); ++i)
    if (m_slam->models()[i].family == motion::EMotionFamily::General) pGeneral += mu[i];
  const int need = pGeneral < 0.5 ? m_slam->options().min_visible_features : m_opts.starved_below;
  if (!holding && m_opts.starved_below > 0 && inView < need)
  {
    std::unordered_set<std::int64_t> copies;
    for (const auto& c : m_probation) copies.insert(c.first);
    const auto rel = m_shadow->releaseUnresolved(need - inView, m_opts.release_min_measured, copies);
    m_frame.released = static_cast<int>(rel.size());
    promotions.insert(promotions.end(), rel.begin(), rel.end());
  }
  std::vector<Vec2> uv;
  std::vector<std::pair<double, double>> prior;
  std::vector<std::int64_t> ids;
  for (const auto& p : promotions)
  {
    uv.push_back(p.uv);
    prior.emplace_back(p.rho, p.sigmaRho);
    ids.push_back(p.id);
  }
  m_frame.promoted = countAdded(m_slam->addFeaturesAt(grey, uv, prior, ids));
  int pendingVisible = 0;
  // Watched features do not count as SLAM's: they are not there for SLAM (watch_features).
  m_watchedVisible = 0;
  for (const auto& v : srep.views)
    if (v.cls == shadow::EShadowClass::Pending && v.searched)
      ++(m_watched.count(v.id) || m_probation.count(v.id) ? m_watchedVisible : pendingVisible);
  // Outcomes of the pending features that left the shadow filter this frame (pendingWeight()).
  const int became = srep.nPromoted + m_frame.released;
  m_becameSlam = kOutcomeDecay * m_becameSlam + became;
  // (A feature held alone leaves the pending ones when it is held, not when it is decided.)
  m_left = kOutcomeDecay * m_left + became + srep.nNewDynamic - srep.nLoneDecided + srep.nLone + srep.nLost +
           srep.nTimedOut;
  return pendingVisible;
}

int CMonoSlamSystem::newFeaturesWanted(int slamInView, int pendingVisible, bool holding, bool& firstMap) const
{
  // SLAM with nothing in view measures no camera motion: a new first map of [slam] initial_features,
  // as at the first frame, straight in SLAM even with the shadow filter, which could only classify
  // against a dead-reckoned camera (the IMM's stationary and rotation models keep the depths open).
  const auto& so = m_slam->options();
  firstMap = !holding && slamInView + m_frame.promoted == 0;
  const int visible = slamInView + static_cast<int>(std::lround(pendingWeight() * pendingVisible));
  return holding    ? 0
         : firstMap ? so.initial_features
                    : std::clamp(so.min_visible_features - visible, 0, so.max_new_features_per_frame);
}

const TSystemFrame& CMonoSlamSystem::processFrame(double timestamp, const cv::Mat& grey, const cv::Mat& excluded)
{
  const auto t0 = Clock::now();
  m_frame = TSystemFrame();
  m_slam->setExclusionMask(excluded);
  m_frame.slam = &m_slam->processFrame(timestamp, grey);
  const auto& rep = *m_frame.slam;
  if (rep.frame > 0)
  {
    // SLAM features expected in view: none of a map the SLAM has given up (lost, not relocalised).
    const int slamInView = m_slam->mapGivenUp() ? 0 : rep.nPredicted;
    // Lost and holding the map for relocalisation: nothing is placed with a pose known to be wrong.
    const bool holding = m_slam->relocalising();
    int pendingVisible = 0;
    std::vector<Vec2> avoid;
    if (m_shadow)
    {
      const auto ts = Clock::now();
      m_shadow->observeMap(rep.frame, mapInliers(rep));
      const auto& srep = m_shadow->processFrame(cameraMotion(timestamp, rep.dtFrames), grey, excluded);
      m_frame.shadow = &srep;
      pendingVisible = promoteFromShadow(srep, grey, holding, slamInView);
      handOver(rep, grey);
      avoid = m_shadow->occupiedPixels();
      m_frame.shadowMs = msSince(ts);
    }
    // Map management: new features where the image is empty of SLAM and shadow features.
    bool firstMap = false;
    const int want = newFeaturesWanted(slamInView, pendingVisible, holding, firstMap);
    if (want > 0)
    {
      std::vector<Vec2> uv;
      for (const auto& c : m_slam->findNewFeatureCandidates(grey, want, avoid)) uv.push_back(c.uv);
      if (m_shadow && !firstMap)
        m_frame.newShadow = static_cast<int>(m_shadow->addFeatures(grey, uv).size());
      else
      {
        const auto added = m_slam->addFeaturesAt(grey, uv);
        if (firstMap) m_frame.newFirstMap = countAdded(added);
        if (firstMap && m_shadow) startProbation(grey, added);
      }
    }
    if (m_shadow && !holding && !firstMap)
      addWatchedFeatures(grey, pendingVisible + m_watchedVisible + m_frame.newShadow, m_shadow->occupiedPixels());
  }
  else if (m_shadow)
  {
    // The first map: nothing to classify it against yet; its copies are classified from now on.
    std::vector<std::int64_t> ids;
    for (const auto& f : m_slam->features()) ids.push_back(f.id);
    startProbation(grey, ids);
  }
  endFrame(timestamp);
  m_frame.totalMs = msSince(t0);
  return m_frame;
}

const TSystemFrame& CMonoSlamSystem::processMeasurements(double timestamp,
                                                         const std::vector<std::pair<std::int64_t, Vec2>>& z,
                                                         bool robust)
{
  const auto t0 = Clock::now();
  m_frame = TSystemFrame();
  // The filter holding each of the caller's tracks now (features leave both by deletion, drops, time-outs).
  std::unordered_set<std::int64_t> inSlam, inShadow;
  for (const auto& f : m_slam->features()) inSlam.insert(f.id);
  if (m_shadow)
    for (const auto& f : m_shadow->features()) inShadow.insert(f.id);
  // A track whose feature left both filters is a new track again: forget it (bounded memory).
  for (auto it = m_trackToFeature.begin(); it != m_trackToFeature.end();)
    it = inSlam.count(it->second) || inShadow.count(it->second) ? std::next(it) : m_trackToFeature.erase(it);
  std::vector<std::pair<std::int64_t, Vec2>> zSlam, zShadow, fresh;
  std::unordered_set<std::int64_t> seen;
  for (const auto& [track, uv] : z)
  {
    if (!uv.allFinite() || !seen.insert(track).second) continue;  // one measurement per track and frame
    const auto it = m_trackToFeature.find(track);
    const std::int64_t id = it == m_trackToFeature.end() ? -1 : it->second;
    if (id >= 0 && inSlam.count(id))
      zSlam.emplace_back(id, uv);
    else if (id >= 0 && inShadow.count(id))
      zShadow.emplace_back(id, uv);
    else if (m_slam->camera().isInImage(uv))
      fresh.emplace_back(track, uv);
  }
  // The SLAM step of processFrame with these matches (gating, 1-point RANSAC, deletion), or every one used.
  m_frame.slam = &m_slam->processMeasurements(timestamp, zSlam, robust);
  const auto& rep = *m_frame.slam;
  const int slamInView = m_slam->mapGivenUp() ? 0 : rep.nPredicted;
  const bool holding = m_slam->relocalising();
  std::vector<Vec2> avoid;
  for (const auto& m : zSlam) avoid.push_back(m.second);
  int pendingVisible = 0;
  if (m_shadow && rep.frame > 0)
  {
    const auto ts = Clock::now();
    m_shadow->observeMap(rep.frame, mapInliers(rep));
    const auto& srep = m_shadow->processMeasurements(cameraMotion(timestamp, rep.dtFrames), zShadow);
    m_frame.shadow = &srep;
    pendingVisible = promoteFromShadow(srep, cv::Mat(), holding, slamInView);
    const auto moved = handOver(rep, cv::Mat());
    if (!moved.empty())
    {
      std::unordered_map<std::int64_t, std::int64_t> newId(moved.begin(), moved.end());
      for (auto& [track, id] : m_trackToFeature)
        if (const auto it = newId.find(id); it != newId.end()) id = it->second;
    }
    for (const auto& m : zShadow) avoid.push_back(m.second);
    m_frame.shadowMs = msSince(ts);
  }
  bool firstMap = false;
  const int want = newFeaturesWanted(slamInView, pendingVisible, holding, firstMap);
  if (want > 0 && !fresh.empty())
  {
    std::vector<std::int64_t> tracks;
    std::vector<Vec2> uv;
    farthestTracks(fresh, avoid, want, tracks, uv);
    std::vector<std::int64_t> ids;
    if (m_shadow && !firstMap)
    {
      ids = m_shadow->addFeatures(cv::Mat(), uv);
      m_frame.newShadow = countAdded(ids);
    }
    else
    {
      ids = m_slam->addFeaturesAt(cv::Mat(), uv);
      if (firstMap) m_frame.newFirstMap = countAdded(ids);
    }
    for (std::size_t k = 0; k < ids.size(); ++k)
      if (ids[k] >= 0) m_trackToFeature[tracks[k]] = ids[k];
  }
  endFrame(timestamp);
  m_frame.totalMs = msSince(t0);
  return m_frame;
}

double CMonoSlamSystem::notTranslatingProbability() const
{
  double p = 0;
  const VecX mu = m_slam->modelProbabilities();
  for (int i = 0; i < mu.size(); ++i)
    if (m_slam->models()[i].family != motion::EMotionFamily::General) p += mu[i];
  return p;
}

void CMonoSlamSystem::retireWatched(std::vector<shadow::TPromotion>& promotions)
{
  if (m_watched.empty()) return;
  // Watched features observe; they never enter SLAM (which takes its own features as before).
  const Vec4 q = m_slam->cameraOrientation();
  const std::int64_t until = m_slam->lastReport().frame + m_shadowOpts.max_pending_frames;
  std::vector<shadow::TPromotion> kept;
  for (auto& p : promotions)
  {
    if (!m_watched.erase(p.id))
    {
      kept.push_back(p);
      continue;
    }
    m_retired.emplace_back(math::quatRotate(q, m_slam->camera().unproject(p.uv).unitVector()), until);
    ++m_frame.retired;
  }
  promotions = std::move(kept);
}

void CMonoSlamSystem::addWatchedFeatures(const cv::Mat& grey, int pendingSearched, std::vector<Vec2> avoid)
{
  if (m_opts.watch_features <= 0) return;
  // Forget watched ids that left the shadow filter (decided dynamic, lost, timed out).
  std::unordered_set<std::int64_t> held;
  for (const auto& f : m_shadow->features())
    if (m_watched.count(f.id)) held.insert(f.id);
  m_watched.swap(held);
  // A translating camera renews its features as the view changes: new ones reach the shadow filter
  // anyway. Watching is for a camera that the bank says does not translate (its map stays complete).
  const int want = notTranslatingProbability() < 0.5 ? 0
                                         : std::clamp(m_opts.watch_features - pendingSearched, 0,
                                                      m_slam->options().max_new_features_per_frame);
  if (want == 0) return;
  // Retired bearings, seen through the current orientation (a still or rotating camera sees them
  // there; a translating one only roughly, for a while), stay clear of new watched features.
  const std::int64_t frame = m_slam->lastReport().frame;
  m_retired.erase(std::remove_if(m_retired.begin(), m_retired.end(), [&](const auto& r) { return r.second < frame; }),
                  m_retired.end());
  const Vec4 qInv = math::quatConjugate(m_slam->cameraOrientation());
  for (const auto& r : m_retired)
  {
    Vec2 uv;
    if (m_slam->camera().project(math::quatRotate(qInv, r.first), uv)) avoid.push_back(uv);
  }
  std::vector<Vec2> uv;
  for (const auto& c : m_slam->findNewFeatureCandidates(grey, want, avoid, 2)) uv.push_back(c.uv);
  for (std::int64_t id : m_shadow->addFeatures(grey, uv))
    if (id >= 0)
    {
      m_watched.insert(id);
      ++m_frame.newWatch;
      ++m_frame.newShadow;
    }
}

double CMonoSlamSystem::pendingWeight() const
{
  if (m_pendingWeight >= 0) return m_pendingWeight;
  // The recent fraction of pending features that ended in SLAM (promoted static, or released), with
  // a prior of one each way: in a static scene most pending features become SLAM features and count
  // almost fully; where many are on moving objects (decided dynamic, lost) they count less, and more
  // candidates are detected for the static world.
  return (1.0 + m_becameSlam) / (2.0 + m_left);
}

void CMonoSlamSystem::effectiveConfig(const mrpt::config::CConfigFileBase& cfg, mrpt::config::CConfigFileBase& out)
{
  TOptions o;
  TSearchOptions se;
  slam::CMonoSlamIMM::TOptions so;
  slam::TIMMBankOptions bo;
  slam::COnePointRansac::TOptions ro;
  shadow::CShadowFilter::TOptions sh;
  o.loadFromConfigFile(cfg, "system");
  se.loadFromConfigFile(cfg, "search");
  so.loadFromConfigFile(cfg, "slam");
  bo.loadFromConfigFile(cfg, "imm");
  ro.loadFromConfigFile(cfg, "ransac");
  sh.loadFromConfigFile(cfg, "shadow");
  o.saveToConfigFile(out, "system");
  se.saveToConfigFile(out, "search");
  so.saveToConfigFile(out, "slam");
  bo.saveToConfigFile(out, "imm");
  ro.saveToConfigFile(out, "ransac");
  sh.saveToConfigFile(out, "shadow");
}

std::map<std::string, std::set<std::string>> CMonoSlamSystem::knownKeys()
{
  return {{"system", core::knownKeys(TOptions(), "system")},
          {"search", core::knownKeys(TSearchOptions(), "search")},
          {"slam", core::knownKeys(slam::CMonoSlamIMM::TOptions(), "slam")},
          {"imm", core::knownKeys(slam::TIMMBankOptions(), "imm")},
          {"ransac", core::knownKeys(slam::COnePointRansac::TOptions(), "ransac")},
          {"shadow", core::knownKeys(shadow::CShadowFilter::TOptions(), "shadow")}};
}
}  // namespace immslam::system
