/* imm-monoslam — the SLAM tracker: the image work around the IMM SLAM filter (CImmSlamFilter).
 *
 * Roles as in Stone Soup: the filter predicts and updates and knows no image; this class associates
 * (active search in the fused ellipses, or given matches gated by them; 1-point RANSAC; the rescue of
 * high-innovation inliers), decides the map policy (deletion rule, ID -> XYZ conversion, bounded map),
 * keeps the features' appearance (templates), detects new corners, handles lost tracking
 * (relocalisation: FAST + PnP) and the exclusion masks. Per frame (processFrame):
 *  1. the filter's IMM mixing and mode-matched prediction (Fig. 2 step 1); relocalisation first when lost;
 *  2. per feature, h = h(x_hat) and S_i from the fused prediction (eqs. 10-14): one active search per
 *     feature inside its 95 % ellipse, shared by the whole bank;
 *  3. 1-point RANSAC on the fused prediction -> low-innovation inliers; the filter updates every mode
 *     with them; high-innovation inliers are rescued and update every mode too;
 *  4. model probabilities from the joint likelihood of all measurements of each mode (eq. 3);
 *  5. map management: deletion of features that fail too often, inverse depth -> XYZ conversion
 *     (linearity index, paper ref. [3]), bounded map size.
 * Known data association (processMeasurements) is the same "associate, then update" flow with the
 * matches given instead of searched. New features are added by the caller (addFeaturesAt) so that a
 * shadow filter can hold them first; findNewFeatureCandidates() proposes corners in empty regions.
 * No file output and no GUI. */
#pragma once

#include <immslam/camera/CCameraModel.h>
#include <immslam/frontend/frontend.h>
#include <immslam/slam/CImmSlamFilter.h>
#include <immslam/slam/COnePointRansac.h>
#include <immslam/slam/TFeature.h>
#include <immslam/slam/TFrameReport.h>
#include <immslam/slam/TIMMBankOptions.h>

#include <mrpt/config/CLoadableOptions.h>
#include <opencv2/core/mat.hpp>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <random>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace immslam::slam
{
class CSlamTracker
{
 public:
  /** Options of the SLAM (section [slam]): the filter's share (filterOptions()) and the tracker's. Noise
   * in pixels: the dimensionless formulation. */
  struct TOptions : public mrpt::config::CLoadableOptions
  {
    double sigma_pixel = 1.0;                   ///< image measurement noise (px); initial value if adaptive
    bool adaptive_pixel_noise = true;           ///< estimate the measurement noise online (CImmSlamFilter::adaptMeasurementNoise)
    /** Raise the loosest models' angular acceleration noise when the camera turns more abruptly
     * (CImmSlamFilter::learnMotionNoise). */
    bool adaptive_motion_noise = true;
    /** Learn the camera's angular shake online from the median innovation of the inliers
     * (CImmSlamFilter::learnShake; never below [imm] shake_px). */
    bool adaptive_shake = true;
    // The fields below that are set to a k* constant are not configuration keys (internal constants,
    // CMonoSlamSystem::removedKeys()); the fields stay for tests and library users.
    static constexpr double kAdaptiveNoiseRate = 0.05;  ///< forgetting weight of the noise estimate (doc/estimator.md)
    static constexpr double kMinSigmaPixel = 0.25;      ///< floor of the adaptive noise (px): sharp rendered images
    double adaptive_noise_rate = kAdaptiveNoiseRate;    ///< weight of each frame's estimate (exponential forgetting)
    double min_sigma_pixel = kMinSigmaPixel;    ///< bounds of the adaptive estimate (px)
    double max_sigma_pixel = 3.0;
    double init_rho = 1.0;                      ///< inverse-depth prior mean (dimensionless)
    double init_rho_std = 1.0;                  ///< inverse-depth prior std: 95 % region includes rho = 0
    static constexpr double kInitVelocityStdPx = 5.0;  ///< initial v and w std (px/frame; doc/estimator.md)
    double init_linear_velocity_std_px = kInitVelocityStdPx;   ///< initial v std (image px/frame at unit depth)
    double init_angular_velocity_std_px = kInitVelocityStdPx;  ///< initial w std (image px/frame)
    double frame_rate_hz = 0;                   ///< nominal frame rate; 0: from the first timestamps
    int patch_half_size = 5;                    ///< 11x11 templates
    bool warp_patches = true;                   ///< predict the patch appearance (affine warp)
    double min_ncc = 0.8;                       ///< correlation threshold of a match
    double search_probability = 0.95;           ///< search ellipse probability (2 dof)
    double max_search_half_extent_px = 60;      ///< clip of pathological search regions
    static constexpr double kExpandSearchFactor = 2.0;   ///< expanded search: ellipse axes times this...
    static constexpr double kExpandBelowFraction = 0.5;  ///< ...when fewer than this fraction of searches succeed
    double expand_search_factor = kExpandSearchFactor;   ///< expanded search: ellipse axes x this factor (1: off)...
    double expand_below_fraction = kExpandBelowFraction; ///< ...when fewer than this fraction of searches found a match
    int fast_threshold = 20;
    int grid_cols = 8, grid_rows = 6;           ///< new features go to empty cells of this grid
    static constexpr double kMinCornerDistancePx = 12;  ///< new features at least this far from others (px)
    static constexpr int kBorderPx = 10;                ///< no new features closer to the image border (px)
    static constexpr double kMinShiTomasi = 0.01;       ///< floor of the normalised Shi-Tomasi response
    double min_corner_distance_px = kMinCornerDistancePx;
    int border_px = kBorderPx;
    double min_shi_tomasi = kMinShiTomasi;
    int min_visible_features = 30;              ///< add features when fewer are predicted in view
    int max_new_features_per_frame = 10;
    int initial_features = 30;                  ///< features initialised at the first frame
    int max_map_features = 150;                 ///< bound of the map (oldest-unseen evicted beyond)
    static constexpr int kDeleteMinPredictions = 10;      ///< MonoSLAM's deletion rule (ref. [6]): after 10 searches...
    static constexpr double kDeleteMinMatchRatio = 0.5;   ///< ...matched in fewer than half
    static constexpr double kLinearityThreshold = 0.1;    ///< ID -> XYZ below this linearity index (ref. [3])
    int delete_min_predictions = kDeleteMinPredictions;   ///< MonoSLAM deletion rule: after this many searches...
    double delete_min_match_ratio = kDeleteMinMatchRatio; ///< ...delete if matched/predicted is below this
    bool convert_to_xyz = true;
    double linearity_threshold = kLinearityThreshold;     ///< ID -> XYZ when the linearity index is below (ref. [3])
    /** Relocalisation (relocalise.h). A frame with fewer than 3 measurements used, or with a fifth or
     * less of its searches, while the map holds at least relocalise_min_inliers well-localised features
     * (XYZ, or inverse depth to 25 %) is a lost frame. While lost (up to
     * relocalise_max_frames frames in a row) the failed searches do not count towards the deletion
     * rule, the caller holds new features (relocalising()), and each frame the map's templates are
     * looked for in the whole image: a PnP pose with at least relocalise_min_inliers inliers replaces
     * the prediction (applyPoseCorrection) before the active search. The same is tried at a frame
     * that comes more than relocalise_after_gap frame periods after the last (dropped frames: the
     * motion models' extrapolation over the gap is no prediction to search with). The map is given up
     * early when relocalise_patience attempts in a row see a textured image (at least 4 x
     * relocalise_min_inliers corners) but give no pose: the camera is somewhere the map has never been
     * (or behind a textured occluder), and waiting would only delay the new map. */
    bool relocalise = true;
    static constexpr int kRelocaliseMinInliers = 8;      ///< PnP inliers that accept a relocalisation
    static constexpr int kRelocaliseMaxFrames = 90;      ///< lost frames in a row during which the map is kept
    static constexpr double kRelocaliseAfterGap = 10;    ///< a gap of this many frame periods: search for the map
    static constexpr int kRelocalisePatience = 5;        ///< failed attempts (textured images) before giving the map up
    int relocalise_min_inliers = kRelocaliseMinInliers;
    int relocalise_max_frames = kRelocaliseMaxFrames;
    double relocalise_after_gap = kRelocaliseAfterGap;
    int relocalise_patience = kRelocalisePatience;
    int num_threads = 2;                        ///< worker threads for the bank (1: none)
    int seed = 1;                               ///< RANSAC random seed (determinism)

    void loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s) override;
    void saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const override;
    void validate(const std::string& section) const;
    /** The filter's share of these options. */
    CImmSlamFilter::TOptions filterOptions() const;
  };

  CSlamTracker(const TOptions& opts, const TIMMBankOptions& bank, const COnePointRansac::TOptions& ransac,
               camera::CCameraModel::Ptr cam);
  CSlamTracker(const CSlamTracker&) = delete;
  CSlamTracker& operator=(const CSlamTracker&) = delete;

  /** Processes one frame: prediction, active search, 1-point RANSAC, updates, model probabilities,
   * deletion/conversion. At the first frame only initialises the map (initial_features corners).
   * \param grey 8-bit grey image of the camera's size. Returns the frame's report. */
  const TFrameReport& processFrame(double timestamp, const cv::Mat& grey);

  /** The filter step with externally associated measurements (known data association, no image).
   * \param z (feature id, measured pixel) pairs; unknown ids are ignored.
   * \param robust false (default): every given measurement is used, no deletion (a measurement-level
   * simulation, the consistency tests). true: the step of processFrame with the matches given instead
   * of found in an image: a feature's measurement counts as found if it lies in its search ellipse
   * (search_probability, fused, eqs. 13-14), then 1-point RANSAC, rescue, updates, adaptive pixel
   * noise, the lost state and map management (deletion included) as for images; no relocalisation. */
  const TFrameReport& processMeasurements(double timestamp, const std::vector<std::pair<std::int64_t, Vec2>>& z,
                                          bool robust = false);

  /** Corners of the image in cells empty of current features (predicted positions; none when
   * mapGivenUp()), at most maxNew; `alsoOccupied` are extra positions to avoid (e.g. shadow-filter
   * features); gridScale > 1 divides every cell of the grid into gridScale x gridScale cells. */
  std::vector<frontend::TCorner> findNewFeatureCandidates(const cv::Mat& grey, int maxNew,
                                                          const std::vector<Vec2>& alsoOccupied = {},
                                                          int gridScale = 1) const;

  /** Adds inverse-depth features observed at pixels uv in `grey` (the current frame) to every mode
   * (undelayed initialisation with each mode's own camera estimate), evicting the longest-unseen
   * features beyond max_map_features. rho/sigmaRho per feature default to the [slam] prior. Returns
   * the new ids (-1 where the patch did not fit). With an empty `grey` no patch is stored (features
   * for processMeasurements only). `ids` (optional, same size as uv) gives the features ids from
   * allocateId(). */
  std::vector<std::int64_t> addFeaturesAt(const cv::Mat& grey, const std::vector<Vec2>& uv,
                                          const std::vector<std::pair<double, double>>& rhoPrior = {},
                                          const std::vector<std::int64_t>& ids = {});

  /** Pixels to leave out (e.g. known moving objects): a CV_8UC1 image of the camera's size, non-zero
   * where excluded, or empty for none. Until the next call, no new feature is detected and no match
   * is accepted within patch_half_size of an excluded pixel (a match there counts as not found);
   * call it before processFrame(). The MonoSLAMBOT paper's Fig. 5(a) baseline, "the dynamic
   * features disabled", is this with the renderer's object masks (doc/shadow.md).
   * \throws std::invalid_argument for a mask of another type or size. */
  void setExclusionMask(const cv::Mat& excluded);

  /** A new feature id, unique among the features of this filter and of any tracker that takes its
   * ids from here (the shadow filter). */
  std::int64_t allocateId() { return m_filter.allocateId(); }
  /** Removes features by id from every mode (e.g. caught moving). */
  void removeFeatures(const std::vector<std::int64_t>& ids);

  /** Reports, every frame from frame `lag` on, the camera's motion over the last `lag` frames with the
   * filter's own covariance (TFrameReport::relFrom, relT, relQ, relCov: the relative-pose consistency
   * check of doc/estimator.md): the pose of every frame is cloned into the state for `lag` frames
   * (CImmSlamFilter::clonePose; 7 more states per frame of lag, the estimate otherwise unchanged).
   * 0 (the default): no clones. Call before the first frame. */
  void setRelativePoseLag(int lag) { m_relativeLag = std::max(lag, 0); }

  /** The estimator. */
  const CImmSlamFilter& filter() const { return m_filter; }
  const TFrameReport& lastReport() const { return m_report; }
  const TOptions& options() const { return m_opts; }
  /** Tracking is lost and the map is kept for relocalisation (TOptions::relocalise): callers should not
   * add new features now. */
  bool relocalising() const
  {
    return m_opts.relocalise && m_lostFrames > 0 && m_lostFrames <= m_opts.relocalise_max_frames &&
           m_noMapFrames < m_opts.relocalise_patience;
  }
  /** This frame was a lost frame (TOptions::relocalise's criterion: too few measurements used): the
   * pose is the motion models' prediction, not a measurement. */
  bool lostThisFrame() const { return m_lostFrames > 0; }
  /** Tracking is lost and the map was given up (relocalise_max_frames or relocalise_patience): the
   * features of the map are no longer expected in the image; new ones are needed at once (callers
   * count none of the map's as visible, and findNewFeatureCandidates() ignores their cells). The map's
   * features stay in the state until the deletion rule removes them. */
  bool mapGivenUp() const { return m_opts.relocalise && m_lostFrames > 0 && !relocalising(); }

  // ---- The filter's results (IMM-fused posterior, paper Fig. 2 step 4; CImmSlamFilter) ----
  Vec3 cameraPosition() const { return m_filter.cameraPosition(); }
  Vec4 cameraOrientation() const { return m_filter.cameraOrientation(); }
  Eigen::Matrix<double, 7, 7> cameraPoseCovariance() const { return m_filter.cameraPoseCovariance(); }
  Mat6 velocityCovariance() const { return m_filter.velocityCovariance(); }
  Vec6 velocity() const { return m_filter.velocity(); }
  const VecX& fusedMean() const { return m_filter.fusedMean(); }
  MatX fusedCovarianceBlock(int offset, int len) const { return m_filter.fusedCovarianceBlock(offset, len); }
  MatX fusedCovariance() const { return m_filter.fusedCovariance(); }
  VecX modelProbabilities() const { return m_filter.modelProbabilities(); }
  const std::vector<motion::TMotionModel>& models() const { return m_filter.models(); }
  const std::vector<TFeature>& features() const { return m_filter.features(); }
  const camera::CCameraModel& camera() const { return m_filter.camera(); }
  const bayes::CIMMEstimator& bank() const { return m_filter.bank(); }
  bool depthKnown(const TFeature& f) const { return m_filter.depthKnown(f); }
  Vec3 featurePosition(const TFeature& f) const { return m_filter.featurePosition(f); }
  TFeatureWorldEstimate featureWorldEstimate(const TFeature& f) const { return m_filter.featureWorldEstimate(f); }

 private:
  using Clock = std::chrono::steady_clock;
  void beginFrame(double timestamp);
  void endFrame(Clock::time_point t0);
  /** The start of a frame's step after the first: the filter's prediction, lost-state bookkeeping. */
  void predictStep(double timestamp);
  /** The first frame of processFrame: initial_features corners at the inverse-depth prior. */
  void initialiseMap(const cv::Mat& grey);
  // Association: candidate matches with their fused predictions.
  /** Active search of every visible feature in the image inside its ellipse (eqs. 13-14). */
  std::vector<TCandidate> searchFeatures(const cv::Mat& grey);
  /** searchFeatures() with the matches given (processMeasurements, robust). */
  std::vector<TCandidate> gateMeasurements(const std::vector<std::pair<std::int64_t, Vec2>>& z);
  /** Every given match of a known feature, ungated (processMeasurements, not robust). */
  std::vector<TCandidate> takeMeasurements(const std::vector<std::pair<std::int64_t, Vec2>>& z);
  /** One search record per predicted feature; found ones become candidates. */
  void recordSearch(int k, const Vec2& h, const Mat2F& Jf, const Mat2& S, bool found, const Vec2& z, double score,
                    std::vector<TCandidate>& cands);
  // Update.
  /** After the association: 1-point RANSAC, the filter's updates, rescue, probabilities, statuses,
   * pixel noise, lost state, map management. */
  void associateAndUpdate(std::vector<TCandidate>& cands);
  /** Known association without robustness: every candidate updates the bank, no deletion. */
  void updateWithAll(const std::vector<TCandidate>& cands);
  /** The status of each search record (inlier, rescued, rejected) and the features' rejection runs. */
  void recordStatuses(const std::vector<TCandidate>& cands, const std::vector<char>& used,
                      const std::vector<int>& high);
  // Map policy.
  void manageMap(bool allowDeletion);
  /** Bounded map: removes the longest-unseen features (not visible now) to make room for `incoming`. */
  void evictForRoom(int incoming);
  /** The stored template of a feature (nullptr: none, e.g. added without an image). */
  const frontend::CFeaturePatch* patchOf(std::int64_t id) const;
  // Lost tracking.
  /** Looks for the map in the whole image and, if found, re-expresses every mode in the found pose. */
  bool tryRelocalise(const cv::Mat& grey);
  /** XYZ, or inverse depth with sigma_rho < 25 % of rho: usable by the relocalisation's PnP. */
  bool wellLocalised(const TFeature& f) const;
  /** Lost-frame bookkeeping at the end of a frame (before the map management). */
  void updateLostState();
  /** New features keep this far from the image border: [slam] border_px, at least the stored patch
   * region (2 patch_half_size + 1). The lens mask is eroded by the same margin. */
  int detectionBorderPx() const { return std::max(m_opts.border_px, 2 * m_opts.patch_half_size + 1); }

  TOptions m_opts;
  CImmSlamFilter m_filter;
  COnePointRansac m_ransac;
  std::unordered_map<std::int64_t, frontend::CFeaturePatch> m_patches;  ///< appearance of the features, by id
  cv::Mat m_lensMask;  ///< where new features and relocalisation corners may be (frontend::lensMask; empty: anywhere)
  cv::Mat m_excluded;     ///< setExclusionMask() grown by patch_half_size (non-zero: excluded; empty: none)
  cv::Mat m_detectMask;   ///< where new features and relocalisation corners may be: m_lensMask without m_excluded
  TFrameReport m_report;
  std::mt19937 m_rng;
  int m_lostFrames = 0;     ///< lost frames in a row (TOptions::relocalise)
  Vec3 m_lastTrackedR = Vec3::Zero();    ///< fused T_W_C at the end of the last frame not lost
  Vec4 m_lastTrackedQ = Vec4(1, 0, 0, 0);
  double m_sinceTracked = 0;  ///< frame periods since the end of the last frame not lost
  int m_relativeLag = 0;      ///< setRelativePoseLag()
  std::vector<std::pair<std::int64_t, double>> m_clonedTimes;  ///< (frame, timestamp) of the cloned frames
  int m_noMapFrames = 0;      ///< lost frames in a row whose relocalisation failed on a textured image
  bool m_sawNoMap = false;    ///< this frame's relocalisation attempt failed on a textured image
};
}  // namespace immslam::slam
