/* imm-monoslam — IMM monocular EKF SLAM (Civera, Davison & Montiel, "Interacting Multiple Model
 * Monocular SLAM", ../shared/papers/imm-monocular-slam.md).
 *
 * A bank of r full-covariance EKFs over the camera (r, q, v, w) and an inverse-depth / XYZ point
 * map, in the dimensionless formulation, each under its own motion model (motion/motion_models.h),
 * combined by the IMM (bayes::CIMMEstimator, paper Fig. 2). r = 1 is the single-model baseline
 * (MonoSLAM-style EKF) with no special code path.
 *
 * Per frame (processFrame):
 *  1. IMM mixing (Fig. 2 step 1) and mode-matched prediction of the camera block;
 *  2. IMM-fused prediction (eqs. 10-11) and, per feature, h = h(x_hat) and S_i (eqs. 13-14): one
 *     active search per feature inside its 95 % ellipse, shared by the whole bank;
 *  3. 1-point RANSAC on the fused prediction -> low-innovation inliers; every mode is updated with
 *     them (own linearization); high-innovation inliers are rescued with the updated fused estimate
 *     and update every mode too;
 *  4. model probabilities from the joint likelihood of all measurements of each mode (eq. 3);
 *  5. map management: deletion of features that fail too often, inverse depth -> XYZ conversion
 *     (linearity index, paper ref. [3]), bounded map size.
 * New features are added by the caller (addFeaturesAt) so that a shadow filter can hold them first;
 * findNewFeatureCandidates() proposes corners in empty image regions.
 *
 * The class does no file output and no GUI. */
#pragma once

#include <immslam/bayes/CIMMEstimator.h>
#include <immslam/bayes/ekf_update.h>
#include <immslam/camera/CCameraModel.h>
#include <immslam/frontend/frontend.h>
#include <immslam/motion/motion_models.h>
#include <immslam/slam/COnePointRansac.h>
#include <immslam/slam/TFeature.h>
#include <immslam/slam/robocentric_prediction.h>

#include <mrpt/config/CLoadableOptions.h>
#include <opencv2/core/mat.hpp>

#include <algorithm>
#include <chrono>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

namespace immslam::math
{
class CThreadPool;
}

namespace immslam::slam
{
/** What happened to one feature in one frame (for overlays and statistics). */
struct TSearchRecord
{
  std::int64_t id = -1;
  Vec2 h = Vec2::Zero();      ///< IMM-fused predicted pixel (eq. 13)
  Mat2 S = Mat2::Identity();  ///< IMM-fused innovation covariance (eq. 14)
  bool found = false;         ///< the active search found a match
  Vec2 z = Vec2::Zero();      ///< measured pixel (when found)
  double score = -1;          ///< best ZNCC inside the ellipse (also when below the threshold)
  enum class EStatus
  {
    NotFound,
    LowInnovationInlier,
    RescuedInlier,
    Rejected
  } status = EStatus::NotFound;
};

/** A feature's fused estimate expressed in the world frame (for maps, scenes and overlays). The
 * covariances are those of the feature relative to the current camera (the camera pose's own
 * uncertainty is not added). */
struct TFeatureWorldEstimate
{
  Vec3 p_W = Vec3::Zero();      ///< mean position (inverse depth: anchor + m / max(rho, 1e-3))
  Mat3 cov_W = Mat3::Zero();    ///< covariance of p_W (first order; for inverse depth its Euclidean approximation)
  bool depthKnown = false;
  bool inverseDepth = false;
  Vec3 anchor_W = Vec3::Zero(); ///< inverse depth: anchor in W
  double theta = 0, phi = 0, rho = 0;  ///< inverse depth: ray angles in W and inverse depth
  Mat3 cov_tpr = Mat3::Zero();  ///< inverse depth: covariance of (theta, phi, rho) in W
};

/** Per-frame figures (frame_stats.csv). */
struct TFrameReport
{
  double timestamp = 0;
  std::int64_t frame = 0;
  int nMap = 0;              ///< features in the SLAM state after the frame
  int nPredicted = 0;        ///< features predicted in the image and searched
  int nFound = 0;            ///< searches that found a match
  int nMatched = 0;          ///< measurements used in the update
  int nRejected = 0;         ///< found matches rejected as outliers
  int nLowInnovation = 0, nRescued = 0, nHypotheses = 0;
  double meanSearchAreaPx2 = 0;  ///< mean of pi * 5.991 * sqrt(det S_i) over searched features
  double sigmaPixel = 0;         ///< measurement noise std used in this frame (px)
  int nDepthKnown = 0;       ///< rho - 1.96 sigma_rho > 0, or XYZ
  int nAdded = 0, nDeleted = 0, nConverted = 0;
  double dtFrames = 1;       ///< elapsed time in nominal frame periods
  bool expandedSearch = false;  ///< the expanded search ran (most matches outside their ellipses)
  double timeMs = 0;         ///< wall time of processFrame
  // Stage timings (ms)
  double tPredictMs = 0, tSearchMs = 0, tRansacMs = 0, tUpdateMs = 0, tMapMs = 0;
  int nDormantModes = 0;     ///< IMM modes not updated this frame (TIMMBankOptions::dormant_below)
  int nLazyModes = 0;        ///< of them, modes whose covariance was not predicted either (lazy_prediction)
  int lostFrames = 0;        ///< lost frames in a row before this one (TOptions::relocalise)
  bool relocalised = false;  ///< this frame's pose was found by relocalisation
  int nRelocMatches = 0;     ///< map points matched (unambiguously) by the relocalisation attempt
  int nRelocInliers = 0;     ///< PnP inliers of the relocalisation attempt (0: none tried or failed early)
  double tRelocMs = 0;       ///< time of the relocalisation attempt (ms)
  std::vector<TSearchRecord> searches;
};

/** Motion model bank of the IMM (section [imm]). */
struct TIMMBankOptions : public mrpt::config::CLoadableOptions
{
  /** Space-separated model specs: `stationary`, `rotation:SIGMA_ANG_PX`,
   * `general:SIGMA_PX` or `general:SIGMA_LIN_PX:SIGMA_ANG_PX`. */
  std::string models = "stationary:0.1 rotation:0.1 rotation:0.5 rotation:1 general:0.1 general:0.5 general:1";
  /** r x r row-major Markov matrix pi(j, i) = P(i at k | j at k-1); empty: built from transition_stay. */
  std::vector<double> transition_matrix;
  /** Diagonal of the default Markov matrix; the rest of each row is spread evenly. */
  double transition_stay = 0.995;
  /** How the default Markov matrix lets a general mode be entered (ignored with transition_matrix):
   * "markov": from every mode (the rest of each row spread evenly over all the other modes);
   * "evidence": not from a mode whose linear velocity is fixed at 0 (stationary, rotation): those rows
   * spread (1 - transition_stay) / (r - 1) over the non-general modes only and keep the remainder on
   * the diagonal. The general modes then keep their own history (mixing from a mode with v = 0 and
   * zero variance would pull their velocity, which carries the scale of a monocular map, back to 0
   * every frame) and take over by the likelihood of the measurements from the probability floor
   * (doc/imm.md, "Entering the general modes"). */
  std::string general_entry = "markov";
  /** Initial model probabilities (empty: uniform). */
  std::vector<double> prior;
  /** Lower bound of every model probability (no model dies for ever). */
  double probability_floor = 1e-4;
  /** Dormant modes (a model-set adaptation in the spirit of Li's variable-structure IMM; 0 = the exact
   * IMM, every mode updated). After the likelihoods of the frame's low-innovation matches are known, a
   * mode whose probability given them, mu_{k|k-1} L^(1) normalized, is below this value is dormant for
   * the frame: its likelihood of **all** the frame's measurements is still computed exactly (eq. 3,
   * from its own prediction, so it can win back probability at once), but its covariance is not
   * updated (the O(n^2 m) step); after the probability update it takes the posterior of the most
   * probable updated mode of an equal or richer family (general > rotation > stationary; one mode of
   * each richer family present is kept updated). A dormant mode ends the frame at the floor, where its
   * own history weighs ~pi_ii floor / mu_{k|k-1} (~0.1 with the defaults) in its next mixing. Measured
   * (doc/imm.md): 1e-5 gave the exact IMM's ATE within 2.3 % on 9 of 11 rendered sequences (better on 2);
   * 1e-4 failed on one of them (3.1 % vs 0.75 % of path), 1e-3 on another (9.4 % vs 1.2 %). */
  double dormant_below = 1e-5;
  /** Lazy prediction (with dormant_below > 0): a moving mode that was dormant in the previous frame gets
   * its predicted mean and the blocks of its transition only; the blocks of its predicted covariance
   * that the frame reads (search regions, RANSAC columns, its likelihood) are computed from them in
   * O(n) each, and the O(n^2) covariance prediction runs only if the frame makes it active. Exact: the
   * same numbers as the full prediction, up to rounding. */
  bool lazy_prediction = true;
  /** Zero-mean angular shake of the camera, px per frame (std of a random walk of the orientation,
   * shake_px / f sqrt(dt) rad), in every model: after the stationary model's identity, the rotation
   * and general models' constant-velocity step (motion::TMotionModel::shakePx; doc/imm.md, "Camera
   * shake"). 0 = none (the paper's models). */
  double shake_px = 0.0;

  void loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s) override;
  void saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const override;

  /** The parsed models. \throws std::runtime_error naming [imm] models. */
  std::vector<motion::TMotionModel> parseModels() const;
  /** The Markov matrix (r x r). \throws std::runtime_error naming the key. */
  MatX transitionMatrix(int r) const;
  VecX priorProbabilities(int r) const;
};

class CMonoSlamIMM
{
 public:
  /** Options of the SLAM filter (section [slam]). Noise in pixels: the dimensionless formulation. */
  struct TOptions : public mrpt::config::CLoadableOptions
  {
    double sigma_pixel = 1.0;                   ///< image measurement noise (px); initial value if adaptive
    bool adaptive_pixel_noise = true;           ///< estimate the measurement noise online (see estimateMeasurementNoise)
    double adaptive_noise_rate = 0.05;          ///< weight of each frame's estimate (exponential forgetting)
    double min_sigma_pixel = 0.25;              ///< bounds of the adaptive estimate (px)
    double max_sigma_pixel = 3.0;
    double init_rho = 1.0;                      ///< inverse-depth prior mean (dimensionless)
    double init_rho_std = 1.0;                  ///< inverse-depth prior std: 95 % region includes rho = 0
    double init_linear_velocity_std_px = 5.0;   ///< initial v std (image px/frame at unit depth)
    double init_angular_velocity_std_px = 5.0;  ///< initial w std (image px/frame)
    double frame_rate_hz = 0;                   ///< nominal frame rate; 0: from the first timestamps
    int patch_half_size = 5;                    ///< 11x11 templates
    bool warp_patches = true;                   ///< predict the patch appearance (affine warp)
    double min_ncc = 0.8;                       ///< correlation threshold of a match
    double search_probability = 0.95;           ///< search ellipse probability (2 dof)
    double max_search_half_extent_px = 60;      ///< clip of pathological search regions
    double expand_search_factor = 2.0;          ///< expanded search: ellipse axes x this factor (1: off)...
    double expand_below_fraction = 0.5;         ///< ...when fewer than this fraction of searches found a match
    int fast_threshold = 20;
    int grid_cols = 8, grid_rows = 6;           ///< new features go to empty cells of this grid
    double min_corner_distance_px = 12;
    int border_px = 10;
    double min_shi_tomasi = 0.01;
    int min_visible_features = 30;              ///< add features when fewer are predicted in view
    int max_new_features_per_frame = 10;
    int initial_features = 30;                  ///< features initialised at the first frame
    int max_map_features = 150;                 ///< bound of the map (oldest-unseen evicted beyond)
    int delete_min_predictions = 10;            ///< MonoSLAM deletion rule: after this many searches...
    double delete_min_match_ratio = 0.5;        ///< ...delete if matched/predicted is below this
    bool convert_to_xyz = true;
    double linearity_threshold = 0.1;           ///< ID -> XYZ when the linearity index is below (ref. [3])
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
    int relocalise_min_inliers = 8;
    int relocalise_max_frames = 90;
    double relocalise_after_gap = 10;
    int relocalise_patience = 5;
    int num_threads = 2;                        ///< worker threads for the bank (1: none)
    int seed = 1;                               ///< RANSAC random seed (determinism)

    void loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s) override;
    void saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const override;
    void validate(const std::string& section) const;
  };

  CMonoSlamIMM(const TOptions& opts, const TIMMBankOptions& bank, const COnePointRansac::TOptions& ransac,
               camera::CCameraModel::Ptr cam);
  ~CMonoSlamIMM();
  CMonoSlamIMM(const CMonoSlamIMM&) = delete;
  CMonoSlamIMM& operator=(const CMonoSlamIMM&) = delete;

  /** Processes one frame: prediction, active search, 1-point RANSAC, updates, model probabilities,
   * deletion/conversion. At the first frame only initialises the map (initial_features corners).
   * \param grey 8-bit grey image of the camera's size. Returns the frame's report. */
  const TFrameReport& processFrame(double timestamp, const cv::Mat& grey);

  /** The filter step with externally associated measurements (known data association, no image):
   * IMM mixing and prediction, one update of every mode with all the given measurements (no active
   * search, no RANSAC), model probabilities, ID -> XYZ conversion. For measurement-level
   * simulations (consistency tests) and for callers with their own front end.
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
   * (undelayed initialisation with each mode's own camera estimate). rho/sigmaRho per feature
   * default to the [slam] prior. Returns the new ids (-1 where the patch did not fit). With an empty
   * `grey` no patch is stored (features for processMeasurements only). `ids` (optional, same size
   * as uv) gives the features ids from allocateId(). */
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
   * ids from here (the shadow filter). \param ids optional ids for addFeaturesAt (e.g. a promoted
   * shadow feature keeps its id). */
  std::int64_t allocateId() { return m_nextId++; }

  // ---- Results (IMM-fused posterior, paper Fig. 2 step 4) ----
  /** Camera pose T_W_C: position and quaternion [qw qx qy qz] (from the fused T_C_W). */
  Vec3 cameraPosition() const { return m_rWC; }
  Vec4 cameraOrientation() const { return m_qWC; }
  /** Covariance of [r_W_C; q_W_C] (7x7, first order through the inversion of T_C_W). */
  Eigen::Matrix<double, 7, 7> cameraPoseCovariance() const;
  /** Covariance of the camera velocities (v, w) in the current camera frame (6x6, fused). */
  Mat6 velocityCovariance() const { return fusedCovarianceBlock(motion::kV, 6); }
  /** The fused velocities (v, w) in the current camera frame (length, rad per frame). */
  Vec6 velocity() const { return m_xFused.segment<6>(motion::kV); }
  /** Fused state mean (x only; cheap). The state is camera-centred: (r_CW, q_CW, v, w) then the
   * features in the current camera frame. */
  const VecX& fusedMean() const { return m_xFused; }
  /** Fused covariance block of a state range (cheap, O(r len^2)). */
  MatX fusedCovarianceBlock(int offset, int len) const;
  /** Full fused covariance (O(r n^2)): for tests and consistency checks. */
  MatX fusedCovariance() const;
  /** Posterior model probabilities mu_k. */
  VecX modelProbabilities() const;
  const std::vector<motion::TMotionModel>& models() const { return m_models; }
  const std::vector<TFeature>& features() const { return m_features; }
  const TFrameReport& lastReport() const { return m_report; }
  const camera::CCameraModel& camera() const { return *m_cam; }
  const bayes::CIMMEstimator& bank() const { return *m_imm; }
  const TOptions& options() const { return m_opts; }
  /** True when the feature's depth is estimated: rho - 1.96 sigma_rho > 0, or XYZ. */
  bool depthKnown(const TFeature& f) const;
  /** Euclidean position of a feature in W (fused mean; rho clamped for points near infinity). */
  Vec3 featurePosition(const TFeature& f) const;
  /** The feature's fused estimate in W (position, covariances, inverse-depth view). */
  TFeatureWorldEstimate featureWorldEstimate(const TFeature& f) const;
  /** Tracking is lost and the map is kept for relocalisation (TOptions::relocalise): callers should not
   * add new features now. */
  bool relocalising() const
  {
    return m_opts.relocalise && m_lostFrames > 0 && m_lostFrames <= m_opts.relocalise_max_frames &&
           m_noMapFrames < m_opts.relocalise_patience;
  }
  /** Tracking is lost and the map was given up (relocalise_max_frames or relocalise_patience): the
   * features of the map are no longer expected in the image; new ones are needed at once (callers
   * count none of the map's as visible, and findNewFeatureCandidates() ignores their cells). The map's
   * features stay in the state until the deletion rule removes them. */
  bool mapGivenUp() const { return m_opts.relocalise && m_lostFrames > 0 && !relocalising(); }
  /** Removes features by id from every mode (e.g. caught moving). */
  void removeFeatures(const std::vector<std::int64_t>& ids);

 private:
  void initialiseState();
  void predict(double dt);
  void searchFeatures(const cv::Mat& grey, std::vector<TCandidate>& cands);
  /** The start of a frame's step after the first: time since the last frame, IMM prediction. */
  void predictStep(double timestamp);
  /** searchFeatures() with the matches given (processMeasurements, robust). */
  void gateMeasurements(const std::vector<std::pair<std::int64_t, Vec2>>& z, std::vector<TCandidate>& cands);
  /** After the search: 1-point RANSAC, updates, rescue, probabilities, statuses, fused estimate,
   * pixel noise, lost state, map management. */
  void associateAndUpdate(std::vector<TCandidate>& cands);
  void updateBank(const std::vector<TCandidate>& cands, const std::vector<int>& which, VecX& logLik);
  /** The measurement of mode g for the candidates `use`: innovation nu and sparse Jacobian H. */
  void buildMeasurement(const bayes::TGaussian& g, const std::vector<TCandidate>& cands, const std::vector<int>& use,
                        bayes::CSparseJacobian& H, VecX& nu) const;
  /** ln N(nu; 0, H P_i H^T + R) of mode i's prediction (lazy modes from their transition blocks).
   * \param keep if given, receives P_i H^T and the factor of S of a mode with a full covariance, for its
   * update (not filled for a lazy mode, whose P is not yet its prediction). */
  double modeLogLikelihood(int i, const bayes::CSparseJacobian& H, const VecX& nu, const VecX& Rdiag,
                           bayes::TInnovationFactors* keep = nullptr) const;
  /** Dormant modes take the posterior of the most probable updated mode (after updateProbabilities). */
  void settleDormantModes();
  std::vector<int> rescue(const std::vector<TCandidate>& cands, const std::vector<char>& used);
  void manageMap();
  void beginFrame(double timestamp);
  void endFrame(std::chrono::steady_clock::time_point t0);
  void refreshFused();
  void estimateMeasurementNoise(const std::vector<TCandidate>& cands, const std::vector<int>& inliers);
  /** Blocks and columns of the fused predicted covariance (eq. 11), never formed whole. */
  MatX predictedCovBlock(int off, int len);
  MatX predictedCovColumns(int off, int len);
  /** Mode i's predicted covariance: rows/columns of one state block, from the lazy form if it has one. */
  MatX modePredictedBlock(int i, int off, int len);
  MatX modePredictedColumns(int i, int off, int len);
  /** Runs the deferred covariance prediction of a lazy mode (no-op otherwise). */
  void materialize(int i);
  void updateWorldPose();
  double frameDt(double timestamp);
  /** Looks for the map in the whole image and, if found, re-expresses every mode in the found pose. */
  bool tryRelocalise(const cv::Mat& grey);
  /** XYZ, or inverse depth with sigma_rho < 25 % of rho: usable by the relocalisation's PnP. */
  bool wellLocalised(const TFeature& f) const;
  /** Lost-frame bookkeeping at the end of a frame (before the map management). */
  void updateLostState();

  TOptions m_opts;
  COnePointRansac m_ransac;
  camera::CCameraModel::Ptr m_cam;
  /** New features keep this far from the image border: [slam] border_px, at least the stored patch
   * region (2 patch_half_size + 1). The lens mask is eroded by the same margin. */
  int detectionBorderPx() const { return std::max(m_opts.border_px, 2 * m_opts.patch_half_size + 1); }
  cv::Mat m_lensMask;  ///< where new features and relocalisation corners may be (frontend::lensMask; empty: anywhere)
  cv::Mat m_excluded;     ///< setExclusionMask() grown by patch_half_size (non-zero: excluded; empty: none)
  cv::Mat m_detectMask;   ///< where new features and relocalisation corners may be: m_lensMask without m_excluded
  std::vector<motion::TMotionModel> m_models;
  std::unique_ptr<bayes::CIMMEstimator> m_imm;
  std::unique_ptr<math::CThreadPool> m_pool;
  std::vector<TFeature> m_features;
  VecX m_xFused;         ///< fused posterior mean
  VecX m_xPred;          ///< fused prediction (eq. 10) of the current frame
  VecX m_rescueWeights;  ///< mode weights after the first update (for the rescue test)
  std::vector<MatX> m_scratch;  ///< per-mode buffers of the prediction
  double m_dormantBelow = 0;    ///< TIMMBankOptions::dormant_below
  bool m_dormantDecided = false;  ///< the frame's dormant set is chosen (first update of the frame done)
  std::vector<char> m_dormant;    ///< per mode: not updated this frame
  std::vector<int> m_dormantUse;  ///< candidates whose likelihood the dormant modes already include
  bool m_lazyPrediction = false;  ///< TIMMBankOptions::lazy_prediction (and dormant modes on)
  std::vector<char> m_wasDormant; ///< per mode: dormant in the previous frame
  /** A mode whose covariance prediction is deferred: its P holds P~ = P + E N E^T of the mixed P. */
  struct TLazyMode
  {
    bool active = false;
    std::vector<TTransitionBlock> blocks;
    std::vector<int> blockAt;  ///< transition block of each state offset, -1 elsewhere
    MatX shake;                ///< n x 3 factor of the shake's covariance (shakeFactor), empty if none
  };
  std::vector<TLazyMode> m_lazy;
  /** Per mode: P H^T and the factor of S of the frame's first likelihood, reused by its update. */
  std::vector<bayes::TInnovationFactors> m_factors;
  Vec3 m_rWC = Vec3::Zero();    ///< fused camera pose T_W_C
  Vec4 m_qWC = Vec4(1, 0, 0, 0);
  TFrameReport m_report;
  std::mt19937 m_rng;
  std::int64_t m_frame = -1, m_nextId = 0;
  double m_lastTimestamp = 0, m_framePeriod = 0;
  std::vector<double> m_firstDeltas;
  double m_focal = 1;
  double m_sigmaPixel = 1;  ///< current measurement noise std (px)
  int m_lostFrames = 0;     ///< lost frames in a row (TOptions::relocalise)
  Vec3 m_lastTrackedR = Vec3::Zero();    ///< fused T_W_C at the end of the last frame not lost
  Vec4 m_lastTrackedQ = Vec4(1, 0, 0, 0);
  double m_sinceTracked = 0;  ///< frame periods since the end of the last frame not lost
  int m_noMapFrames = 0;      ///< lost frames in a row whose relocalisation failed on a textured image
  bool m_sawNoMap = false;    ///< this frame's relocalisation attempt failed on a textured image
};
}  // namespace immslam::slam
