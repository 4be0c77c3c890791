/* imm-monoslam — the IMM monocular SLAM filter without images (Civera, Davison & Montiel, "Interacting
 * Multiple Model Monocular SLAM", ../shared/papers/imm-monocular-slam.md).
 *
 * A bank of r full-covariance EKFs over the camera-centred state (r_CW, q_CW, v, w, then the features
 * in the current camera frame), in the dimensionless formulation, each under its own motion model
 * (motion/motion_models.h), combined by the IMM (bayes::CIMMEstimator, paper Fig. 2). r = 1 is the
 * single-model baseline with no special code path. One frame, driven by a tracker (CSlamTracker):
 *
 *   beginFrame(); predict(t);                                   Fig. 2 step 1 + mode-matched prediction
 *   predictedMeasurement() / predictedInnovationCovariance()    eqs. 10-14 (fused prediction, search regions)
 *   ... the tracker associates (search or given matches, 1-point RANSAC) ...
 *   update(matches); [rescueGate(); update(rescued);]           every mode with its own linearisation
 *   finishUpdate();                                             eq. 3, Fig. 2 step 4
 *   reparametrizeMap(), addFeatures(), removeFeatures()         map operations
 *
 * Dormant and lazy modes (TIMMBankOptions::dormant_below, lazy_prediction) are the bank's own policy,
 * invisible to the caller. No image, no OpenCV, no front end, no file output. */
#pragma once

#include <immslam/bayes/CIMMEstimator.h>
#include <immslam/bayes/ekf_update.h>
#include <immslam/camera/CCameraModel.h>
#include <immslam/motion/motion_models.h>
#include <immslam/slam/COnePointRansac.h>
#include <immslam/slam/TFeature.h>
#include <immslam/slam/TFeatureWorldEstimate.h>
#include <immslam/slam/TIMMBankOptions.h>
#include <immslam/slam/measurement.h>
#include <immslam/slam/robocentric_prediction.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

namespace immslam::math
{
class CThreadPool;
}

namespace immslam::slam
{
class CImmSlamFilter
{
 public:
  /** The filter's share of the [slam] options (CSlamTracker::TOptions::filterOptions()). Noise in
   * pixels: the dimensionless formulation. */
  struct TOptions
  {
    double sigma_pixel = 1.0;                   ///< image measurement noise (px); initial value if adaptive
    bool adaptive_pixel_noise = true;           ///< estimate the noise online (adaptMeasurementNoise)
    double adaptive_noise_rate = 0.05;          ///< weight of each frame's estimate (exponential forgetting)
    double min_sigma_pixel = 0.25;              ///< bounds of the adaptive estimate (px)
    double max_sigma_pixel = 3.0;
    /** Raise the angular acceleration noise of the bank's loosest general and rotation models online
     * when the camera's accelerations exceed it (learnMotionNoise; never below the model's own noise). */
    bool adaptive_motion_noise = true;
    int motion_noise_warmup = 10;               ///< frames learned from before the learned noise acts
    /** Learn the camera's angular shake online, from the median innovation of the inliers (learnShake;
     * never below the bank's own shake_px; nothing is learned when that is 0). */
    bool adaptive_shake = true;
    double max_shake_factor = 10.0;             ///< bound of the learned shake, times the bank's shake_px
    double max_motion_noise_factor = 3.0;       ///< bound of the learned noise, times the model's own
    double init_rho = 1.0;                      ///< inverse-depth prior mean (dimensionless)
    double init_rho_std = 1.0;                  ///< inverse-depth prior std
    double init_linear_velocity_std_px = 5.0;   ///< initial v std (image px/frame at unit depth)
    double init_angular_velocity_std_px = 5.0;  ///< initial w std (image px/frame)
    double frame_rate_hz = 0;                   ///< nominal frame rate; 0: from the first timestamps
    int num_threads = 2;                        ///< worker threads for the bank (1: none)
  };

  /** A new inverse-depth feature for addFeatures(): the pixel it is seen at in the current frame and its
   * inverse-depth prior (rho, sigma_rho). */
  struct TNewFeature
  {
    Vec2 uv = Vec2::Zero();
    double rho = 1.0, sigmaRho = 1.0;
    std::int64_t id = -1;  ///< from allocateId() (or an id the caller's other tracker took from there)
  };

  /** Which modes the frame's update left dormant (TIMMBankOptions::dormant_below). */
  struct TModeActivity
  {
    int nDormant = 0;  ///< modes not updated this frame
    int nLazy = 0;     ///< of them, modes whose covariance was not predicted either
  };

  CImmSlamFilter(const TOptions& opts, const TIMMBankOptions& bank, camera::CCameraModel::Ptr cam);
  ~CImmSlamFilter();
  CImmSlamFilter(const CImmSlamFilter&) = delete;
  CImmSlamFilter& operator=(const CImmSlamFilter&) = delete;

  // ---- Time and prediction (Fig. 2 step 1, eqs. 10-11) ----
  /** A new frame begins: returns its number (0 for the first). */
  std::int64_t beginFrame() { return ++m_frame; }
  /** The first frame: the clock starts at `timestamp`; no prediction. */
  void start(double timestamp);
  /** IMM mixing and, per mode, the camera-centred prediction under its motion model, then the fused
   * predicted mean (eq. 10). The elapsed time is counted in nominal frame periods (rounded when within
   * 10 % of a whole number). \return the elapsed time dt in frames. */
  double predict(double timestamp);
  /** The fused predicted mean x_hat (eq. 10) of the current frame. */
  const VecX& predictedMean() const { return m_xPred; }
  /** Diagonal block [off, off + len) of the fused predicted covariance (eq. 11), never formed whole.
   * Thread-safe for feature blocks (lazy modes read their transition blocks). */
  MatX predictedCovBlock(int off, int len);
  /** Columns [off, off + len) of the fused predicted covariance (eq. 11): 1-point RANSAC's gains. */
  MatX predictedCovColumns(int off, int len);
  /** The pixel h_i = h(x_hat) of a feature in the fused prediction (eq. 13) and dh/d(feature).
   * \return false if it is behind the camera or outside the model's domain. */
  bool predictedMeasurement(const TFeature& f, Vec2& h, Mat2F* J_feat = nullptr) const
  {
    return predictMeasurement(*m_cam, m_xPred, f, h, J_feat);
  }
  /** \f$ S_i = H_i \hat P H_i^\top + \sigma^2 I \f$ with the fused predicted covariance (eq. 14):
   * the search region of feature f. Thread-safe (one feature block). */
  Mat2 predictedInnovationCovariance(const TFeature& f, const Mat2F& J_feat)
  {
    return innovationCovariance(predictedCovBlock(f.offset, f.dim()), J_feat, m_sigmaPixel);
  }
  /** Relocalisation: every mode re-expressed in the found pose T_C'W = (r_CW, q_CW), with the pose's
   * own uncertainty (sigmaT, sigmaTheta) and restarted velocities (applyPoseCorrection), then the fused
   * prediction again. */
  void correctPose(const Vec3& r_CW, const Vec4& q_CW, double sigmaT, double sigmaTheta, const Vec6& velocity,
                   const Mat6& velocityCov);

  // ---- Update with given matches ----
  /** Updates every mode with the matches `which` of `cands` (each mode linearises at its own estimate;
   * matches that some mode cannot predict are left out) and adds each mode's log-likelihood of them to
   * the frame's (eq. 3). The first call of a frame also decides the dormant modes: they keep their
   * prediction, their likelihood of all the frame's matches is still exact. Counts nMatched of the
   * features used. \return the number of matches used. */
  int update(const std::vector<TCandidate>& cands, const std::vector<int>& which);
  /** The high-innovation rescue: the candidates not `used` whose innovation against the fused estimate
   * after the first update (weights mu_{k|k-1} L^(1), eqs. 10-11 on the updated modes) passes the
   * chi-square gate `gateChi2` (2 dof). */
  std::vector<int> rescueGate(const std::vector<TCandidate>& cands, const std::vector<char>& used, double gateChi2);
  /** The end of the frame's update: model probabilities from the frame's log-likelihoods (eq. 3), the
   * dormant modes take the posterior of the most probable updated mode of an equal or richer family,
   * fused estimate (Fig. 2 step 4). */
  TModeActivity finishUpdate();
  /** Adaptive pixel noise from the post-fit residuals of the inliers `inliers` of `cands` (Myers &
   * Tapley): blended into sigmaPixel() with TOptions::adaptive_noise_rate, within its bounds. */
  void adaptMeasurementNoise(const std::vector<TCandidate>& cands, const std::vector<int>& inliers);
  /** The camera's shake learned from the median innovation of the inliers `inliers` of `cands` at the
   * fused prediction (TOptions::adaptive_shake; shakePx()). Call before adaptMeasurementNoise: the
   * candidates' S hold the pixel noise of this frame's prediction. */
  void learnShake(const std::vector<TCandidate>& cands, const std::vector<int>& inliers);

  // ---- Map operations (every mode, each with its own linearisation) ----
  /** Undelayed inverse-depth initialisation of new features seen in the current frame, in every mode
   * with that mode's own camera estimate. Returns their ids. */
  std::vector<std::int64_t> addFeatures(const std::vector<TNewFeature>& fresh);
  /** Removes features by id from every mode. */
  void removeFeatures(const std::vector<std::int64_t>& ids);
  /** One re-parametrisation of every mode: features k with drop[k] deleted, those with convert[k]
   * converted from inverse depth to XYZ (paper ref. [3]). */
  void reparametrizeMap(const std::vector<char>& drop, const std::vector<char>& convert);
  /** Linearity index of an inverse-depth feature's conversion to XYZ at the fused estimate (ref. [3]). */
  double linearityIndex(const TFeature& f) const;
  /** A new feature id, unique among this filter's features and those of any tracker taking its ids here. */
  std::int64_t allocateId() { return m_nextId++; }
  /** The track record of feature k (counts of searches and matches; not its place in the state). */
  TFeature& featureRecord(int k) { return m_features[k]; }

  // ---- Pose clones (stochastic cloning; robocentric_prediction.h, poseCloneOffset) ----
  /** Clones the current camera pose: a block T_C_Ck at the identity with no covariance in every mode,
   * between the velocities and the features, which every later prediction carries along as it does
   * the world pose while the updates correlate it with the camera, so that relativePose() gives the
   * camera's motion since the past frame with the filter's own covariance. The clones of
   * frames for which keep(frame) is false are dropped first; at most maxClones slots are held (the
   * oldest clone gives way), recycled in place. Call after the frame's update. */
  void clonePose(const std::function<bool(std::int64_t)>& keep, int maxClones);
  /** Number of clone slots in the state (in use or free). */
  int numClones() const { return static_cast<int>(m_cloneFrames.size()); }
  /** The frame whose pose each clone slot holds, in state order (slot c at poseCloneOffset(c); -1: free). */
  const std::vector<std::int64_t>& cloneSlots() const { return m_cloneFrames; }
  /** The camera's motion since the cloned frame j: T_{C_j C_k} = (T_{C_k C_j})^{-1}, p_Cj = R(q) p_Ck + t,
   * with the covariance of [dt; dtheta] (invertPoseClone of the clone's fused block).
   * \return false when frame j has no clone. */
  bool relativePose(std::int64_t frame, Vec3& t, Vec4& q, Mat6& cov) const;

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
  /** Fused state mean (camera-centred: (r_CW, q_CW, v, w) then the features in the camera frame). */
  const VecX& fusedMean() const { return m_xFused; }
  /** Fused covariance block of a state range (cheap, O(r len^2)). */
  MatX fusedCovarianceBlock(int offset, int len) const;
  /** Full fused covariance (O(r n^2)): for tests and consistency checks. */
  MatX fusedCovariance() const;
  /** Posterior model probabilities mu_k. */
  VecX modelProbabilities() const;
  const std::vector<motion::TMotionModel>& models() const { return m_models; }
  const std::vector<TFeature>& features() const { return m_features; }
  const camera::CCameraModel& camera() const { return *m_cam; }
  const bayes::CIMMEstimator& bank() const { return *m_imm; }
  const TOptions& options() const { return m_opts; }
  /** Current measurement noise std (px). */
  double sigmaPixel() const { return m_sigmaPixel; }
  /** Angular acceleration noise of the bank's loosest general model as the next prediction uses it
   * (px; its own until the camera's accelerations exceed it; 0 without a general model). */
  double loosestAngularNoisePx() const;
  /** The angular shake (px per frame) the next prediction uses: the bank's shake_px, or the learned
   * one where it exceeds it (TOptions::adaptive_shake). */
  double shakePx() const;
  /** Mean focal length (px): the scale of the dimensionless formulation. */
  double focal() const { return m_focal; }
  std::int64_t frame() const { return m_frame; }
  /** True when the feature's depth is estimated: rho - 1.96 sigma_rho > 0, or XYZ. */
  bool depthKnown(const TFeature& f) const;
  /** Euclidean position of a feature in W (fused mean; rho clamped for points near infinity). */
  Vec3 featurePosition(const TFeature& f) const;
  /** The feature's fused estimate in W (position, covariances, inverse-depth view). */
  TFeatureWorldEstimate featureWorldEstimate(const TFeature& f) const;
  /** The bank's thread pool ([slam] num_threads), for the caller's per-feature work. */
  math::CThreadPool& threadPool() { return *m_pool; }

 private:
  void initialiseState();
  double frameDt(double timestamp);
  /** The first update of a frame: every mode's likelihood, the dormant set, the others' update. */
  void firstUpdate(const std::vector<TCandidate>& cands, const std::vector<int>& use, const VecX& Rdiag);
  /** A later update: dormant modes re-score all the frame's matches, the others are updated. */
  void laterUpdate(const std::vector<TCandidate>& cands, const std::vector<int>& use, const VecX& Rdiag);
  /** Picks the dormant modes from a = ln mu_{k|k-1} + ln L^(1) (one mode of each richer family kept). */
  void chooseDormantModes(const VecX& a);
  /** The measurement of mode g for the candidates `use`: innovation nu and sparse Jacobian H. */
  void buildMeasurement(const bayes::TGaussian& g, const std::vector<TCandidate>& cands, const std::vector<int>& use,
                        bayes::CSparseJacobian& H, VecX& nu) const;
  /** ln N(nu; 0, H P_i H^T + R) of mode i's prediction (lazy modes from their transition blocks).
   * \param keep if given, receives P_i H^T and the factor of S of a mode with a full covariance. */
  double modeLogLikelihood(int i, const bayes::CSparseJacobian& H, const VecX& nu, const VecX& Rdiag,
                           bayes::TInnovationFactors* keep = nullptr) const;
  /** Dormant modes take the posterior of the most probable updated mode (after the probabilities). */
  TModeActivity settleDormantModes();
  void refreshFused();
  void updateWorldPose();
  /** Mode i's predicted covariance: rows/columns of one state block, from the lazy form if it has one. */
  MatX modePredictedBlock(int i, int off, int len);
  MatX modePredictedColumns(int i, int off, int len);
  /** Runs the deferred covariance prediction of a lazy mode (no-op otherwise). */
  void materialize(int i);

  TOptions m_opts;
  camera::CCameraModel::Ptr m_cam;
  std::vector<motion::TMotionModel> m_models;
  std::unique_ptr<bayes::CIMMEstimator> m_imm;
  std::unique_ptr<math::CThreadPool> m_pool;
  std::vector<TFeature> m_features;
  std::vector<std::int64_t> m_cloneFrames;  ///< frame of the pose clone in each slot (clonePose), -1: free
  /** Size of the camera and clone blocks: the first feature's offset. */
  int headDim() const { return poseCloneOffset(numClones()); }
  VecX m_xFused;         ///< fused posterior mean
  VecX m_xPred;          ///< fused prediction (eq. 10) of the current frame
  VecX m_logLik;         ///< per mode: ln-likelihood of the frame's matches so far (eq. 3)
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
  std::int64_t m_frame = -1, m_nextId = 0;
  double m_lastTimestamp = 0, m_framePeriod = 0;
  std::vector<double> m_firstDeltas;
  double m_focal = 1;
  double m_sigmaPixel = 1;  ///< current measurement noise std (px)
  /** The loosest models' angular acceleration noise learned online (TOptions::adaptive_motion_noise). */
  struct TMotionNoise
  {
    int general = -1, rotation = -1;  ///< the loosest general and rotation modes (-1: none in the bank)
    double angular2 = 0;              ///< learned angular acceleration variance (px^2 per frame^2)
    int frames = 0;                   ///< frames learned from
    bool primed = false;              ///< this frame's prediction of `general` is recorded below
    Vec3 wPred = Vec3::Zero();        ///< its predicted angular velocity
    Mat3 PwwPred = Mat3::Zero();      ///< and its predicted covariance
    double usedAngular2 = 0, dt = 1;  ///< the noise and the interval of that prediction
    double shake2 = -1;               ///< learned shake variance (px^2 per frame; < 0: not yet)
    int shakeFrames = 0;              ///< frames it was learned from
  };
  /** Model i as predicted now: the loosest general and rotation models with the learned noise. */
  motion::TMotionModel effectiveModel(int i) const;
  /** Covariance matching of the loosest general mode's angular velocity correction of this frame. */
  void learnMotionNoise();
  TMotionNoise m_motionNoise;
};
}  // namespace immslam::slam
