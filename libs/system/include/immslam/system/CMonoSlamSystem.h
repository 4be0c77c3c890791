/* imm-monoslam — the full system of the two papers wired together (MonoSLAMBOT Fig. 1): the IMM SLAM
 * filter estimates the camera and the static map; the shadow filter holds every new feature until it
 * is classified static (promoted into SLAM, with the shadow's inverse-depth estimate) or dynamic
 * (tracked, its trajectory output). SLAM features that start moving (rejected as outliers frame after
 * frame) are handed back to the shadow filter. This class only wires the two; it owns no maths. */
#pragma once

#include <immslam/camera/CCameraModel.h>
#include <immslam/tracking/CShadowTracker.h>
#include <immslam/tracking/CMonoSlamIMM.h>

#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/config/CLoadableOptions.h>
#include <opencv2/core/mat.hpp>

#include <deque>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <unordered_map>
#include <unordered_set>

namespace immslam::system
{
/** A past position of a dynamic track taken from the map: a SLAM feature that turned out to move
 * (handed over, or a first-map feature whose probation copy was decided dynamic) was held static
 * there, from its first observation to its last inlier. Rows of tracks.csv written at the track's
 * dynamic decision, before its own rows. */
struct TMappedPast
{
  std::int64_t id = -1;       ///< the dynamic track's id
  double timestamp = 0;       ///< when it was seen there
  Vec3 p_W = Vec3::Zero();    ///< the map's estimate of its position (SLAM lengths)
  Vec2 uv = Vec2::Zero();     ///< the pixel it was seen at then
  double range = 0;           ///< distance from the camera then
  double rangeRelSigma = 0;   ///< relative 1-sigma of that distance (the map's)
};

/** Result of one frame of the whole system. */
struct TSystemFrame
{
  const slam::TFrameReport* slam = nullptr;      ///< the SLAM filter's report (valid until the next frame)
  const shadow::TShadowReport* shadow = nullptr; ///< the shadow filter's report, or null (off / first frame)
  int promoted = 0;     ///< shadow features promoted into SLAM this frame (static or released)
  int released = 0;     ///< of which released unresolved (SLAM short of features)
  int handedOver = 0;   ///< SLAM features handed to the shadow filter (caught moving)
  int newShadow = 0;    ///< new features given to the shadow filter
  /** New features put straight into SLAM as a new first map: SLAM had no feature in view, so there was
   * no measured camera motion to classify anything against (a blank start, a map given up, a view
   * the map has left entirely). */
  int newFirstMap = 0;
  int newWatch = 0;     ///< of newShadow, the ones only watched (SLAM did not need them)
  int retired = 0;      ///< watched features decided static (never promoted into SLAM)
  /** First-map features removed from SLAM because their probation copy was decided dynamic. */
  int firstMapMovers = 0;
  /** The mapped past of the tracks decided dynamic in this frame (TMappedPast). */
  std::vector<TMappedPast> mappedPast;
  double shadowMs = 0;  ///< wall time of the shadow filter
  double totalMs = 0;   ///< wall time of processFrame (image decoding excluded)
};

class CMonoSlamSystem
{
 public:
  /** Options of the wiring (section [system]). */
  struct TOptions : public mrpt::config::CLoadableOptions
  {
    /** New features go first to the MonoSLAMBOT shadow filter (true) or straight into SLAM (false). */
    bool shadow_filter = true;
    /** A SLAM feature found but rejected as an outlier in this many consecutive frames is removed from
     * SLAM and re-initialised in the shadow filter (it may have started to move). 0: never. */
    int handover_rejections = 3;
    /** Pending shadow features that cannot be classified for lack of parallax but were never rejected
     * are released into SLAM with their unresolved inverse depth when SLAM has fewer features in view
     * than [slam] min_visible_features while the IMM says the camera does not translate (stationary
     * and rotation families), or fewer than this number whatever the motion. 0: never. */
    int starved_below = 20;
    /** ... if tracked for at least this many frames. */
    int release_min_measured = 10;
    /** Weight of a pending shadow feature (searched in this frame) in the count of features in view
     * that decides how many new features to detect ([slam] min_visible_features): a number in [0, 1],
     * or "auto": the recent fraction of pending features that ended in SLAM (see pendingWeight()). */
    std::string pending_weight = "auto";
    /** While the IMM bank says the camera does not translate (stationary and rotation families
     * above 0.5), the shadow filter keeps at least this many pending features in view, detected on a
     * grid twice as fine as SLAM's wherever no other feature is, whether SLAM needs features or not:
     * so that things that move are seen even while the map is complete (a still camera watching
     * people, a camera panning a room; a translating camera renews its features anyway). Watched
     * features only observe: decided dynamic, they are tracked; decided static, they are retired
     * (never promoted into SLAM, their bearing kept clear of new watched features for
     * max_pending_frames frames). 0: new features only when SLAM needs them (MonoSLAMBOT's policy). */
    int watch_features = 10;
    /** The weight of a pending_weight text: the number, or -1 for "auto".
     * \throws std::runtime_error naming [section] pending_weight if it is neither. */
    static double parsePendingWeight(const std::string& text, const std::string& section);
    void loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s) override;
    void saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const override;
  };

  /** The active search, shared by both filters (section [search]): one camera, one matcher. The SLAM
   * filter and the shadow filter search their predicted ellipses (Civera et al. eqs. 10-14) with the
   * same template size, warp, correlation threshold and ellipse probability. The image noise is
   * [slam] sigma_pixel for both (the shadow filter takes its initial value), and so is the
   * inverse-depth prior ([slam] init_rho, init_rho_std). */
  struct TSearchOptions : public mrpt::config::CLoadableOptions
  {
    int patch_half_size = 5;                ///< template half size (5 -> 11x11 px)
    bool warp_patches = true;               ///< predict the patch appearance by an affine warp
    double min_ncc = 0.8;                   ///< minimum zero-mean NCC of a match
    double search_probability = 0.95;       ///< probability of the search ellipse (2 dof)
    double max_search_half_extent_px = 60;  ///< clip of very large search regions (px)
    void loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s) override;
    void saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const override;
    /** Copies the search block, the image noise and the depth prior into both filters' options. */
    void applyTo(slam::CMonoSlamIMM::TOptions& slamOpts, shadow::CShadowFilter::TOptions& shadowOpts) const;
  };

  /** Loads [system], [search], [slam], [imm], [ransac] and [shadow] from cfg.
   * \throws std::runtime_error naming the section/key of a bad value. */
  CMonoSlamSystem(const mrpt::config::CConfigFileBase& cfg, camera::CCameraModel::Ptr cam);
  ~CMonoSlamSystem();

  /** Processes one 8-bit grey frame of the camera's size. `excluded` (optional, CV_8UC1 of the same
   * size, non-zero where excluded): pixels where no new feature starts and no SLAM match is accepted
   * in this frame (CMonoSlamIMM::setExclusionMask; [input] exclusion_masks). */
  const TSystemFrame& processFrame(double timestamp, const cv::Mat& grey, const cv::Mat& excluded = cv::Mat());

  /** The same step with known data association and no image: the caller's own front end, or a
   * measurement-level simulation such as MonoSLAMBOT's Fig. 5 experiment ("data association was
   * performed manually", Sec. IV). z holds (track id, measured pixel) with the caller's own track ids,
   * at most one per track. A track the system holds is measured by the filter that holds it:
   * - SLAM runs the step of processFrame with these matches (CMonoSlamIMM::processMeasurements,
   *   robust): a measurement outside its feature's search ellipse is not found, then 1-point RANSAC,
   *   updates, deletion; no relocalisation;
   * - the shadow filter runs CShadowFilter::processMeasurements.
   * Tracks the system does not hold are taken as the image step takes new corners: the first map of
   * [slam] initial_features at the first frame (or whenever SLAM has nothing in view), then, while
   * fewer than [slam] min_visible_features are in view, up to max_new_features_per_frame of them, those
   * farthest from the features held, into the shadow filter (into SLAM when it is off). Promotions,
   * releases and handovers are those of processFrame (a handed-over track keeps its track id with the
   * shadow feature's new id). A track whose feature has left both filters (deleted, lost, timed out)
   * may be taken again as a new feature, with a new id. The reports' feature ids are the system's own.
   * \param robust false: SLAM uses every measurement given (no gate, no RANSAC, no deletion, hence no
   * handover): the paper's classic MonoSLAM with manual data association. */
  const TSystemFrame& processMeasurements(double timestamp, const std::vector<std::pair<std::int64_t, Vec2>>& z,
                                          bool robust = true);

  const slam::CMonoSlamIMM& slam() const { return *m_slam; }
  slam::CMonoSlamIMM& slam() { return *m_slam; }
  /** The shadow filter, or null when off. */
  const shadow::CShadowFilter* shadowFilter() const { return m_shadow ? &m_shadow->filter() : nullptr; }
  const TOptions& options() const { return m_opts; }
  /** The weight of a pending shadow feature in the count of features in view now: [system]
   * pending_weight, or with "auto" (1 + b) / (2 + n), b and n the pending features that ended in SLAM
   * (promoted or released) and that left the shadow filter in any way (also decided dynamic, lost,
   * timed out), both decayed by 0.99 per frame (about the last 100 frames). */
  double pendingWeight() const;

  /** Loads every section's options from cfg (defaults where absent) and writes them, with their
   * comments, into out: the effective configuration without building the system. */
  static void effectiveConfig(const mrpt::config::CConfigFileBase& cfg, mrpt::config::CConfigFileBase& out);
  /** Keys known per section (for the unknown-key check of the application). */
  static std::map<std::string, std::set<std::string>> knownKeys();
  /** Keys that older configs may hold and that were removed or moved: "[section] key" -> what replaced
   * it (the application's key check names both). */
  static const std::map<std::string, std::string>& removedKeys();

 private:
  shadow::TCameraMotion cameraMotion(double timestamp, double dt) const;
  /** The bank's probability that the camera does not translate (stationary and rotation families). */
  double notTranslatingProbability() const;
  /** Promotions and releases of the shadow filter's frame into SLAM, and the outcome counts of
   * pendingWeight(); returns the pending features searched in the frame that are not watched. */
  int promoteFromShadow(const shadow::TShadowReport& srep, const cv::Mat& grey, bool holding, int slamInView);
  /** SLAM features rejected in handover_rejections frames in a row move to the shadow filter (at
   * their pixel in grey); returns the (SLAM id, new shadow id) pairs. */
  std::vector<std::pair<std::int64_t, std::int64_t>> handOver(const slam::TFrameReport& rep, const cv::Mat& grey);
  /** How many new features the frame wants; firstMap: they start a new first map straight in SLAM. */
  int newFeaturesWanted(int slamInView, int pendingVisible, bool holding, bool& firstMap) const;
  /** New watched features (watch_features) where no feature is, none near a retired bearing. */
  void addWatchedFeatures(const cv::Mat& grey, int pendingSearched, std::vector<Vec2> avoid);
  /** Retires the promotions of watched features (they never enter SLAM). */
  void retireWatched(std::vector<shadow::TPromotion>& promotions);
  /** Probation of a first map (features put straight into SLAM, nothing to classify them against):
   * a copy of each goes to the shadow filter at its pixel. */
  void startProbation(const cv::Mat& grey, const std::vector<std::int64_t>& slamIds);
  /** The copies' decisions: static keeps the SLAM feature (the copy is not promoted),
   * dynamic removes the SLAM feature (its mapped past goes to the copy's track). Also forgets the
   * mapped past of tracks that left the shadow filter and emits that of tracks decided dynamic. */
  void settleProbation(const shadow::TShadowReport& srep, std::vector<shadow::TPromotion>& promotions);
  /** Where a SLAM feature was mapped, as rows of the track `trackId` (TMappedPast). */
  std::vector<TMappedPast> mappedPast(const slam::TFeature& f, std::int64_t trackId) const;
  /** Keeps the camera centre (mapped pasts' ranges) and pose (next frame's motion) of this frame. */
  void endFrame(double timestamp);
  /** Its pixel in the current camera (false: behind it). */
  bool pixelOf(const slam::TFeature& f, Vec2& uv) const;

  TOptions m_opts;
  TSearchOptions m_searchOpts;
  slam::CMonoSlamIMM::TOptions m_slamOpts;
  slam::TIMMBankOptions m_bankOpts;
  slam::COnePointRansac::TOptions m_ransacOpts;
  shadow::CShadowFilter::TOptions m_shadowOpts;
  std::unique_ptr<slam::CMonoSlamIMM> m_slam;
  std::unique_ptr<shadow::CShadowTracker> m_shadow;
  TSystemFrame m_frame;
  double m_pendingWeight = 1.0;        ///< fixed [system] pending_weight (< 0: auto)
  double m_becameSlam = 0, m_left = 0; ///< decayed counts of pending features that left the shadow filter
  std::unordered_map<std::int64_t, std::int64_t> m_trackToFeature;  ///< processMeasurements: caller's track -> feature id
  std::unordered_set<std::int64_t> m_watched;  ///< shadow features started by watch_features
  int m_watchedVisible = 0;                    ///< of them, pending and searched in this frame
  /** Retired watched features: unit bearing in W and the frame until which it is kept clear. */
  std::vector<std::pair<Vec3, std::int64_t>> m_retired;
  /** Probation copies in the shadow filter: copy id -> the SLAM feature it tests (startProbation). */
  std::unordered_map<std::int64_t, std::int64_t> m_probation;
  /** Mapped past of shadow features that left the map, emitted at their dynamic decision. */
  std::unordered_map<std::int64_t, std::vector<TMappedPast>> m_pastOf;
  /** Recent camera centres by timestamp (ranges of TMappedPast), at most kCameraPathFrames. */
  std::deque<std::pair<double, Vec3>> m_cameraPath;
  Vec3 m_prevR = Vec3::Zero();
  Vec4 m_prevQ = Vec4(1, 0, 0, 0);
};
}  // namespace immslam::system
