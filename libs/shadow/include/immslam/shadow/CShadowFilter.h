/* imm-monoslam — the MonoSLAMBOT "Shadow Filter" (Migliore et al., ../shared/papers/
 * monoslambot-shadow-filter.md, Fig. 1 and Sec. III): a bearing-only tracker that holds every NEW
 * feature until it is classified static (then promoted into the SLAM filter) or dynamic (then kept
 * and tracked, its trajectory output).
 *
 * Per frame the SLAM filter gives the camera pose and its motion since the previous frame
 * (TCameraMotion); the shadow filter
 *  1. predicts every feature's EKF with the camera increment (eq. 2, feature_ekf.h): predict(),
 *     which also gives each feature's predicted pixel and 95 % innovation ellipse;
 *  2. takes the frame's associations (searched, found at a pixel) and updates each found feature's
 *     EKF (eqs. 3-5): update(). The image search is the caller's (tracking::CShadowTracker searches
 *     with the features' patches; processMeasurements() takes known associations);
 *  3. classifies the pending features (Sec. III-A, eqs. 6-14, CRayClassifier) and
 *  4. reports decisions, promotions (removed from the shadow filter), dynamic tracks in W, and drops
 *     pending features that time out or are lost and dynamic ones lost for too long: finishFrame().
 * New features are added by the caller after the frame (addFeatures), at pixels of the frame just
 * processed. A frame whose camera motion the SLAM did not measure (TCameraMotion::measured: lost
 * tracking, a relocalisation) is predicted and updated as any other, but nothing is classified in it,
 * and the pending features' views start again after it. Estimator library: no image, no OpenCV, no front end, no GUI, no file output. */
#pragma once

#include <immslam/camera/CCameraModel.h>
#include <immslam/shadow/CRayClassifier.h>
#include <immslam/shadow/feature_ekf.h>
#include <immslam/shadow/shadow_types.h>

#include <mrpt/config/CLoadableOptions.h>

#include <chrono>
#include <cstdint>
#include <functional>
#include <unordered_set>
#include <utility>
#include <vector>

namespace immslam::shadow
{
/** One feature held by the shadow filter. */
struct TShadowFeature
{
  std::int64_t id = -1;
  EShadowClass cls = EShadowClass::Pending;  ///< Pending or Dynamic
  TShadowState ekf;                          ///< eqs. (1)-(5)
  TRayTrack track;                           ///< views for the classifier (relative poses in C0)
  std::int64_t firstFrame = 0;
  double age = 0;                            ///< frames (nominal periods) since its first observation
  /** The camera motion since its last view was not measured (TCameraMotion::measured): its views
   * (track) start again at its next measurement in a measured frame. */
  bool restartViews = false;
  int missed = 0;                            ///< consecutive frames without a match
  int nMeasured = 0;                         ///< frames with a match (the first observation included)
  Vec2 predicted = Vec2::Zero();             ///< predicted pixel of this frame
  Mat2 S = Mat2::Identity();                 ///< innovation covariance of this frame
  Vec2 uv = Vec2::Zero();                    ///< last measured pixel
  bool searched = false, measured = false;   ///< in this frame
  double score = 0;                          ///< ZNCC of this frame's match (0: not measured)
  std::vector<float> scores;                 ///< ZNCC of its matches while pending (TShadowMatch::score)
  /** Its rays do not meet, but its template does not follow one point (TOptions::min_point_ncc): motion
   * seen there, no decision made. Held like a dynamic feature (cls Dynamic: a static decision among
   * such features waits), never reported as a decision or a track. */
  bool incoherent = false;
  /** Motion seen while no other feature nearby moved (CShadowFilter::classifyAndManage): held like an
   * incoherent feature, and decided dynamic (with `loneVerdict`) once another one there moves too. */
  bool lone = false;
  TDecision loneVerdict;
  /** A copy of a feature the SLAM map holds (setMapCopies): its dynamic verdict is decided alone, since
   * the map uses the point while it waits. */
  bool mapCopy = false;
};

/** One feature's association in a frame (CShadowFilter::update): searched for, and found at uv or not. */
struct TShadowMatch
{
  std::int64_t id = -1;
  bool found = false;
  Vec2 uv = Vec2::Zero();  ///< the measured pixel (when found)
  double score = 1.0;      ///< the match's ZNCC against the feature's template (1: not known)
};

/** The shadow filter (see the file comment; README.md in libs/shadow for the formulation and the
 * measured figures). */
class CShadowFilter
{
 public:
  /** Options (section [shadow]). Noise in pixels: the dimensionless formulation (doc/conventions.md):
   * an acceleration of s px means s / f length units per frame^2 (the image motion a point at unit
   * depth would show). */
  struct TOptions : public mrpt::config::CLoadableOptions
  {
    // -- EKF (Sec. III)
    double sigma_pixel = 1.0;            ///< measurement noise std (px)
    double init_rho = 1.0;               ///< prior mean of w = inverse distance (1 = unit distance)
    double init_rho_std = 1.0;           ///< prior std of w (its 95 % region includes 0 = infinity)
    static constexpr double kInitVelocityStdPx = 5.0;  ///< velocity prior std (px/frame at unit depth)
    double init_velocity_std_px = kInitVelocityStdPx;  ///< velocity prior std (px/frame at unit depth)
    double sigma_accel_px = 0.5;         ///< acceleration noise (px/frame^2 at unit depth)
    // -- Active search (the image side: CShadowTracker in libs/tracking)
    int patch_half_size = 5;             ///< 11x11 templates
    bool warp_patches = true;            ///< predict the patch appearance (affine warp)
    double min_ncc = 0.8;                ///< correlation threshold of a match
    double search_probability = 0.95;    ///< probability of the search ellipse (2 dof)
    double max_search_half_extent_px = 60;
    // -- Classifier (Sec. III-A). The k* constants are not configuration keys (the decision rule's
    // internals, doc/shadow.md); the fields stay for tests and library users.
    static constexpr double kAlpha = 0.05;              ///< significance of the three-ray test (eq. 14)
    static constexpr int kMinTestFrames = 3;            ///< first test once the views span 3 frames
    static constexpr int kDynamicRejections = 5;        ///< dynamic: 5 rejections ...
    static constexpr int kDynamicWindow = 5;            ///< ... in the last 5 tests
    static constexpr int kStaticAcceptances = 5;        ///< static: 5 consecutive acceptances ...
    static constexpr int kStaticMinFrames = 10;         ///< ... a track of 10 frames ...
    static constexpr double kStaticMinVelocityPx = 1.0; ///< ... power against 1 px/frame ...
    static constexpr double kStaticPower = 0.95;        ///< ... with detection probability 0.95
    double alpha = kAlpha;               ///< significance of the three-ray test (eq. 14)
    int min_test_frames = kMinTestFrames;         ///< first test once the feature's views span this many frames
    int dynamic_rejections = kDynamicRejections;  ///< dynamic when this many of ...
    int dynamic_window = kDynamicWindow;          ///< ... the last this-many tests reject
    int static_acceptances = kStaticAcceptances;  ///< static: consecutive acceptances ...
    int static_min_frames = kStaticMinFrames;     ///< ... a track at least this long ...
    double static_min_velocity_px = kStaticMinVelocityPx; ///< ... and power against this speed (px/frame at the point's distance)
    double static_power = kStaticPower;  ///< ... with this detection probability
    bool static_power_worst_case = true; ///< ... in every direction (else on average over directions)
    /** While the camera does not translate (TCameraMotion::pNotTranslating >= 0.5), a static decision
     * waits until the feature's track is this long, so that slow image motion has had the time to
     * show in the depth-free test (a mover at a turning point or pausing, one moving along its line
     * of sight); waiting costs the map little there (SLAM takes the unresolved features it needs;
     * doc/shadow.md, "Decision rules"). At most static_min_frames: no wait. */
    static constexpr int kStillCameraStaticFrames = 30;
    int still_camera_static_frames = kStillCameraStaticFrames;
    /** A dynamic decision needs a track that follows one point: the median ZNCC of the feature's matches
     * while pending at least this. A patch born across the edge of a moving object (half background,
     * half object) slides along that edge while the object passes and stops where it leaves: its rays
     * do not meet, yet it is no point of the object, and where it stops it is the background. Such a
     * feature becomes TShadowFeature::incoherent (doc/shadow.md, "Decision rules"). Measured on the
     * still and rotating camera renders: median ZNCC 0.95 for the decisions on movers, 0.86 for the
     * dynamic decisions on the background. 0: no check. */
    static constexpr double kMinPointNcc = 0.87;
    double min_point_ncc = kMinPointNcc;
    /** [shadow] decide_lone_dynamic: a dynamic verdict of a translating camera is decided at once even
     * when no other feature nearby moves (within an eighth of the image width). false (the default):
     * such a feature is held as motion seen (TShadowFeature::lone) until another one there moves; on a
     * static real scene nearly every false dynamic decision is such a lone track (doc/shadow.md,
     * "Decision rules"). true: the papers' filter, for movers seen by one feature each (their
     * random-point experiments). */
    bool decide_lone_dynamic = false;
    // -- Management
    static constexpr int kMaxPendingFrames = 150;       ///< undecided features dropped after 150 frames
    static constexpr int kMaxMissedFrames = 5;          ///< pending features dropped after 5 misses in a row
    static constexpr int kDynamicMaxMissedFrames = 10;  ///< dynamic features dropped after 10 misses in a row
    int max_pending_frames = kMaxPendingFrames;  ///< undecided features are dropped after this many frames
    int max_missed_frames = kMaxMissedFrames;    ///< pending features dropped after this many misses in a row
    int dynamic_max_missed_frames = kDynamicMaxMissedFrames;  ///< dynamic features dropped after this many misses in a row
    int max_features = 100;              ///< addFeatures refuses beyond this many held features
    double min_inverse_distance = 1e-3;  ///< w clamp when placing tracks in W

    void loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s) override;
    void saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const override;
    /** \throws std::runtime_error naming [section] key of a value out of range. */
    void validate(const std::string& section) const;
    /** The classifier's parameters. */
    TRayClassifierParams classifierParams() const;
  };

  /** Returns a new feature id, unique across SLAM and shadow features. */
  using IdAllocator = std::function<std::int64_t()>;
  /** First id of the filter's own numbering (no allocator given: the filter alone, in tests). */
  static constexpr std::int64_t kFirstOwnId = 1000000000;

  /** \param ids optional id allocator (e.g. the SLAM's); without it ids count from
   * kFirstOwnId. \throws std::runtime_error on a null camera or invalid options. */
  CShadowFilter(const TOptions& opts, camera::CCameraModel::Ptr cam, IdAllocator ids = {});

  /** Begins a frame: prediction (eq. 2) of every feature with the camera motion, its predicted pixel
   * and innovation covariance (TShadowFeature::predicted, S: the search region).
   * \throws std::runtime_error on an invalid motion. */
  void predict(const TCameraMotion& motion);
  /** The frame's associations: each match marks its feature searched and, when found, updates its
   * EKF with the pixel (eqs. 3-5). One measurement per feature and frame (later ones ignored);
   * unknown ids are ignored. Features not in `matches` count as not searched. */
  void update(const std::vector<TShadowMatch>& matches);
  /** Ends the frame: classification (Sec. III-A), drops, the report. \param searchMs the caller's
   * association time, reported as tSearchMs. The report stays valid until the next frame. */
  const TShadowReport& finishFrame(double searchMs = 0);

  /** One frame with known data association (measurement-level simulations, callers with their own
   * front end): predict(), update() with z (feature id, measured pixel; non-finite pixels ignored),
   * finishFrame(). Features absent from z count as missed; unknown ids are ignored. */
  const TShadowReport& processMeasurements(const TCameraMotion& motion,
                                           const std::vector<std::pair<std::int64_t, Vec2>>& z);

  /** New features observed at pixels uv of the frame just processed (call after that frame's
   * finishFrame; before the first frame the camera is taken as W's origin). Returns the ids (-1:
   * refused, e.g. max_features reached or not a finite pixel). Every feature starts from the [slam]
   * init_rho, init_rho_std prior, a SLAM feature handed over too: the map's depth was estimated as if
   * it did not move, and as a prior it took the three-ray test's power (a pasted mover's moving ->
   * static rate 0.3 -> 1.4 %). */
  std::vector<std::int64_t> addFeatures(const std::vector<Vec2>& uv);

  /** Measured or predicted pixels of all held features (to keep new detections away). */
  std::vector<Vec2> occupiedPixels() const;

  /** Features waiting for a classification. */
  std::size_t numPending() const;
  /** Features classified dynamic and still tracked. */
  std::size_t numDynamic() const;
  /** All held features (pending + dynamic). */
  std::size_t size() const { return m_features.size(); }

  /** Pending features that cannot be classified yet for lack of parallax (a stationary or rotating
   * camera) but look static so far: measured in this frame, at least minMeasured frames old, never
   * rejected by the three-ray test. Up to maxCount of them (oldest first) leave the shadow filter and
   * are returned as promotions with the shadow EKF's inverse depth (whose prior, without parallax,
   * still includes infinity). The system uses this only when the SLAM filter runs short of features;
   * a moving one is caught later by SLAM's outlier rejection and handed back. Features whose id is in
   * notReleased stay (e.g. copies of features SLAM already holds). */
  std::vector<TPromotion> releaseUnresolved(int maxCount, int minMeasured,
                                            const std::unordered_set<std::int64_t>& notReleased = {});
  /** The held features (read-only, for overlays and tests). */
  const std::vector<TShadowFeature>& features() const { return m_features; }
  /** The feature with this id, or nullptr. */
  const TShadowFeature* feature(std::int64_t id) const;
  /** Removes features by id (e.g. matched by the caller to something else). */
  void removeFeatures(const std::vector<std::int64_t>& ids);
  /** Marks features as copies of features the SLAM map holds, or no longer (TShadowFeature::mapCopy). */
  void setMapCopies(const std::vector<std::int64_t>& ids, bool copies);

  /** The SLAM map's measurements of frame `frame` (its inliers: id, pixel), given before that frame's
   * processFrame/processMeasurements: the reference of the three-ray test (CRayClassifier::mapScale). */
  void observeMap(std::int64_t frame, std::vector<std::pair<std::int64_t, Vec2>> z) { m_map.add(frame, std::move(z)); }

  /** The report of the last processed frame. */
  const TShadowReport& lastReport() const { return m_report; }
  /** The options in use (validated). */
  const TOptions& options() const { return m_opts; }
  /** The static/dynamic classifier (Sec. III-A). */
  const CRayClassifier& classifier() const { return m_classifier; }
  /** The camera model. */
  const camera::CCameraModel& camera() const { return *m_cam; }

  /** A dynamic feature's world position, covariance and velocity from the current pose. */
  TTrackPoint trackPoint(const TShadowFeature& f) const;

 private:
  void beginFrame(const TCameraMotion& motion);
  void predictAll(const TCameraMotion& motion);
  void updateFeature(TShadowFeature& f, const Vec2& z);
  void classifyAndManage();
  /** The classifier's verdict on a pending feature in this frame (classifyAndManage). */
  struct TVerdict
  {
    EShadowClass c = EShadowClass::Pending;
    TDecision info;
    TRayTestResult r;
  };
  /** The verdicts on the healthy pending features (by index into m_features; Pending for the others);
   * the pixels of the dynamic ones are appended to dynamicVerdictUv. */
  std::vector<TVerdict> classifyPending(const std::vector<Vec2>& dynamicUv, double radius,
                                        std::vector<Vec2>& dynamicVerdictUv);
  /** Applies verdict v to the pending feature f (othersMove: another feature near it moves); false when
   * f leaves the filter (promoted). */
  bool decide(TShadowFeature& f, const TVerdict& v, bool othersMove);
  /** Whether f stays (not lost, timed out or dropped; those are counted in the report). */
  bool keep(const TShadowFeature& f, bool healthy);
  /** Whether the feature's matches follow one point (TOptions::min_point_ncc). */
  bool followsOnePoint(const TShadowFeature& f) const;
  /** Adds the decision c on f (the classifier's figures in info) to this frame's report. */
  void recordDecision(const TShadowFeature& f, EShadowClass c, TDecision info);
  void endFrame();
  TPromotion makePromotion(const TShadowFeature& f, const TRayTestResult& r) const;

  TOptions m_opts;
  camera::CCameraModel::Ptr m_cam;
  CRayClassifier m_classifier;
  IdAllocator m_ids;
  std::int64_t m_nextId = 0;
  std::vector<TShadowFeature> m_features;
  TCameraMotion m_motion;  ///< the current frame's motion
  bool m_started = false;
  TShadowReport m_report;
  CMapViews m_map;  ///< the SLAM map's recent measurements (observeMap)
  double m_sigmaV = 0, m_sigmaA = 0;  ///< in length units per frame (per frame^2)
  std::chrono::steady_clock::time_point m_t0;  ///< start of the current frame
};
}  // namespace immslam::shadow
