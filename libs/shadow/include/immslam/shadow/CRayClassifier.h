/* imm-monoslam — the shadow filter's static/dynamic classifier (MonoSLAMBOT paper, Sec. III-A,
 * eqs. 6-14): three uncertain viewing rays of a feature must meet in one point. */
#pragma once

#include <immslam/camera/CCameraModel.h>
#include <immslam/geometry/ray_incidence.h>
#include <immslam/shadow/CMapViews.h>
#include <immslam/shadow/depth_free_test.h>
#include <immslam/shadow/relative_pose.h>
#include <immslam/shadow/shadow_types.h>

#include <cstdint>
#include <limits>
#include <vector>

namespace immslam::shadow
{
/** One measured view of a feature, in the frame of its first view \f$ C_0 \f$. */
struct TRayView
{
  std::int64_t frame = 0;
  double time = 0;          ///< frames since the first observation
  Vec2 uv = Vec2::Zero();   ///< measured pixel
  TUncertainPose T_0j;      ///< camera of this view w.r.t. \f$ C_0 \f$, with the relative covariance
};

/** What the classifier keeps about one feature: its measured views and the relative motion of the
 * current camera since the first view, composed from the SLAM increments. */
struct TRayTrack
{
  std::vector<TRayView> views;  ///< measured views, views[0] the first observation (identity pose)
  TUncertainPose T_0k;          ///< the current camera w.r.t. \f$ C_0 \f$ (every frame, measured or not)
  double elapsed = 0;           ///< frames since the first observation
  std::int64_t frame = 0;       ///< current frame
  std::vector<char> recent;     ///< results of the last evaluations (1: rejected), oldest first
  int acceptStreak = 0;         ///< consecutive accepted evaluations up to now
  int evaluations = 0;          ///< valid tests so far
  int rejections = 0;           ///< rejected tests so far
  double detectionProbability = 0;  ///< last power figure computed (detectionProbability())
  /** The smallest probability, over the frames since the first view, that the camera did not
   * translate (TCameraMotion::pNotTranslating). */
  double notTranslating = 1;

  /** Starts the track at its first observation. */
  void start(std::int64_t frame, const Vec2& uv);
  /** One frame later: \f$ T_{0k} \leftarrow T_{0k}\,T_{k-1,k} \f$ (composePoses) with the increment
   * (t, dq) and its covariance; pNotTranslating as TCameraMotion's. */
  void advance(std::int64_t frame, double dt, const Vec3& t, const Vec4& dq, const Mat6& cov,
               double pNotTranslating = 0);
  /** Records the current frame's measurement as a view (at the current T_0k). */
  void addView(const Vec2& uv);
};

/** Result of testing one triple of views. */
struct TRayTestResult
{
  bool evaluated = false;           ///< enough views and a valid test
  geometry::TRayIncidenceTest test; ///< threeRaysMeet's result (test.T, threshold, intersection in C0)
  int viewIndex[3] = {0, 0, 0};     ///< indices into TRayTrack::views: first, intermediate, current
  MatX cov_rays;                    ///< 18x18 joint covariance of the three rays (Plücker, in C0)
  geometry::TUncertainLine3 rays[3];
  double parallaxRad = 0;           ///< widest angle between the three rays
  TDepthFreeTest depthFree;         ///< the depth-free test of the same three views
  /** A static decision whose power came from the depth-free test alone: the rays lack the parallax
   * to triangulate, so the promotion is a ray of unknown depth. */
  bool staticByDepthFree = false;
};

/** Parameters of the classifier (loaded by CShadowFilter::TOptions, section [shadow]). */
struct TRayClassifierParams
{
  double alpha = 0.05;            ///< significance of each test (eq. 14)
  double sigmaPx = 1.0;           ///< pixel noise of every measured view
  int minTestFrames = 3;          ///< first test once the track spans this many frames
  int dynamicRejections = 5;      ///< dynamic when at least this many of ...
  int dynamicWindow = 5;          ///< ... the last this-many tests rejected
  int staticAcceptances = 5;      ///< static needs this many consecutive accepted tests ...
  int staticMinFrames = 10;       ///< ... a track at least this long ...
  double staticMinVelocityPx = 1.0; ///< ... and power against this speed (px/frame at the point's distance)
  double staticPower = 0.95;      ///< detection probability that defines "power"
  bool staticWorstCase = true;    ///< power in every direction (true) or on average over directions
  /** Largest inverse distance a static point may have in the depth-free test (the shadow EKF's
   * prior: init_rho + 3 init_rho_std). */
  double maxInverseDistance = 4.0;
};

/** The classifier.
 *
 * Test (eqs. 6-14, geometry::threeRaysMeet). The three viewing rays of the feature — first view,
 * the measured view closest in time to halfway, the current view — are built as uncertain Plücker
 * lines in the frame of the *first* camera \f$ C_0 \f$: ray j joins the centre \f$ t_{0j} \f$ with the
 * point at infinity of \f$ R_{0j}\,\mathrm{unproject}(uv_j) \f$. Their joint 18x18 covariance comes
 * from the pixel noise (sigmaPx, independent per view) and from the *relative* poses
 * \f$ T_{0m}, T_{0k} \f$ composed from the SLAM increments, including their correlation
 * \f$ \mathrm{Cov}(\delta_k, \delta_m) = \Phi\,\Sigma_m \f$ (perturbationTransport): the chain to k
 * contains the chain to m. Using absolute SLAM poses with their absolute covariances instead would
 * count the drift shared by all views as independent errors and let moving points pass as static.
 *
 * The map as the reference (not in the paper). The composed covariance assumes independent
 * increments; an EKF's are correlated through its velocity estimate, and on real video the SLAM
 * filter is over-confident for stretches of frames, so static points are rejected far above alpha,
 * all at once (doc/shadow.md). Every point in the same views shares that error, the map's static
 * points too. So a rejection must also stand against the map: with a CMapViews (the SLAM filter's
 * inliers of each recent frame), the same test is run for up to 8 map points measured in the same
 * three frames with the same relative poses, and the feature's statistic is compared with the
 * threshold times $ \max(1, \mathrm{median}(T_{map}) / \mathrm{median}(\chi^2_3)) $ (mapScale()).
 * With a right covariance the median of the map's statistics is that of a chi-square and nothing
 * changes; with a covariance k times too small it is about k times larger and so is the threshold.
 * Only rejections are re-examined (acceptances and the static decision's power stay as they are), so
 * a static decision is never made easier. Measured on simulated tracks with 4x over-confident poses:
 * a static point's rejection rate 64 % alone, 1 % against the map; a mover at 2 px per frame 96 % and
 * 80 % (shadow_classifier_unittest, TheMapAbsorbsAnOverConfidentRelativeMotion).
 *
 * Decisions.
 * - Dynamic: at least dynamicRejections of the last dynamicWindow valid tests rejected. Successive
 *   tests share views 0 and m and are strongly correlated, so a static point's rejections come in
 *   runs; requiring 5 of the last 5 keeps the lifetime false-dynamic rate near 1 % (3 of 5: 15 %)
 *   with single tests at alpha = 5 % (measured, shadow_classifier_unittest).
 * - Static: the current test accepted, staticAcceptances consecutive acceptances, the track spans
 *   staticMinFrames, and the test has *power*: a point moving at constant velocity V (in \f$ C_0 \f$,
 *   from view 0, displaced by \f$ V\tau_j \f$ at view j) at speed staticMinVelocityPx, in pixels per
 *   frame at the point's distance from the current camera (\f$ |V| f / \mathrm{dist} \f$), would
 *   have been rejected by the current test with probability >= staticPower — in *every* direction
 *   (staticWorstCase, the default) or on average over uniformly random directions.
 *   The non-centrality of the test for a velocity V is quadratic, \f$ \lambda(V) = V^\top A V \f$
 *   (velocityNoncentrality(): the first-order sensitivity of the reduced test vector to V through the
 *   same construction as geometry::threeRaysMeet, evaluated on exact rays through the triangulated
 *   point; checked against threeRaysMeet in shadow_model_unittest); the detection probability of a
 *   direction e is the non-central chi-square tail \f$ P(\chi'^2_3(\lambda) > \chi^2_{1-\alpha;3}) \f$
 *   (tabulated once), with \f$ \lambda = s^2 e^\top A e \f$: worst case
 *   \f$ \lambda_{min}(A) \f$, average over 128 fixed directions otherwise.
 *   The weakest direction is, at small parallax, *along the viewing ray*: a point sliding along its
 *   ray changes the three-ray geometry only by (parallax angle) x (displacement), so the test
 *   sees it late (signal-to-noise ~ \f$ c\,s\,\tau_m(\tau_k - \tau_m)/(D\sigma) \f$ for parallax rate c,
 *   speed s, distance D, angular noise \f$ \sigma \f$: maximal with the intermediate view halfway).
 *   The worst-case criterion therefore waits for parallax (mean 3.4 s for hand-held motion at
 *   0.36 units/s, depths 1-5); the average criterion promotes after ~1.5 s but lets most slow
 *   along-ray movers through. Motions exactly explained by a static point at another depth are
 *   undetectable by any test on these rays.
 * - Velocities of the shadow EKF are never used (poorly observable after initialisation, Sec. III-A).
 *
 * The depth-free test (depth_free_test.h) runs beside the three-ray test on the same three views,
 * weighted by \f$ \pi_{nt} \f$, the smallest probability, over the track's frames, that the camera did
 * not translate (the IMM's stationary and rotation families). A frame's evaluation rejects when the
 * three-ray test rejects, or the depth-free test does while \f$ \pi_{nt} \ge 0.5 \f$ (with translation
 * it stays valid but only as good as the relative motion's covariance, which the three-ray test
 * already uses to the full). A static decision needs power, a mixture of the two tests' through the bank:
 * \f$ \max(P_{rays},\; \pi_{nt} P_{df}) \ge \f$ staticPower, with \f$ P_{df} \f$ the depth-free test's
 * worst-direction probability of detecting an image motion of staticMinVelocityPx per frame. The
 * weight matters: image motion is the only evidence a camera that does not translate has, and a point
 * that slides along its own viewing ray shows none; a translating camera can wait for the parallax
 * that reveals it.
 */
class CRayClassifier
{
 public:
  CRayClassifier(const TRayClassifierParams& p, camera::CCameraModel::Ptr cam);

  /** The parameters in use. */
  const TRayClassifierParams& params() const { return m_p; }

  /** Tests the current triple of views (needs >= 3 views, the last one the current frame).
   * The rays and their covariance are left in the result. */
  TRayTestResult test(const TRayTrack& track) const;

  /** The matrix A of the test's non-centrality \f$ \lambda(V) = V^\top A V \f$ for a point that moves
   * with constant velocity V (in \f$ C_0 \f$, length per frame) from view 0, displacing it by
   * \f$ V \tau_j \f$ at view j. Linearized at exact rays through the triangulated point with the
   * tested rays' covariance, through the construction of geometry::threeRaysMeet (spherical
   * normalization, widest pair, concurrencyDistance, reduction of d2 to its two dominant
   * combinations).
   * \param distK optional output: the point's distance from the current camera.
   * \return false when the point is at infinity, behind the first or the current camera, or the
   * construction is degenerate. */
  bool velocityNoncentrality(const TRayTrack& track, const TRayTestResult& r, Mat3& A, double* distK = nullptr) const;

  /** Worst-direction minimum detectable velocity of a tested triple, in pixels per frame at the
   * point's distance: \f$ \sqrt{\lambda_0/\lambda_{min}(A)}\, f / \mathrm{dist} \f$ with \f$ \lambda_0 \f$
   * the non-centrality of power staticPower; +infinity when velocityNoncentrality() fails. */
  double minimumDetectableVelocityPx(const TRayTrack& track, const TRayTestResult& r) const;

  /** Probability that the tested triple detects a point moving at speedPx (pixels per frame at its
   * distance) in a uniformly random direction (average over 128 directions); 0 when
   * velocityNoncentrality() fails. */
  double detectionProbability(const TRayTrack& track, const TRayTestResult& r, double speedPx) const;

  /** Rejection probability of the 3-dof test at level alpha for non-centrality lambda (tabulated). */
  double powerAt(double lambda) const;

  /** Runs the test if the current frame was measured (its view is the last), updates the track's
   * counters and decides: Static, Dynamic or Pending.
   * \param info optional output: the decision's figures (testT, minDetectableVelocityPx).
   * \param map optional: the SLAM map's recent measurements; a three-ray rejection then needs
   * T > mapScale() x threshold (see the class comment). Null: the test alone, as in the paper.
   * \param staticNotBefore no static decision before the track is this long (frames), whatever
   * staticMinFrames says: the caller's own wait (CShadowFilter: a camera that does not translate). */
  EShadowClass classify(TRayTrack& track, TDecision* info = nullptr, TRayTestResult* result = nullptr,
                        const CMapViews* map = nullptr, double staticNotBefore = 0) const;

  /** The map's scale of the three-ray statistic over the views of r: the median statistic of the
   * map's features measured in the same three frames, tested with the same relative poses, over the
   * median of \f$ \chi^2_3 \f$ (at least 1); 1 when fewer than kMinMapFeatures are common. */
  double mapScale(const TRayTrack& track, const TRayTestResult& r, const CMapViews& map) const;

  /** The viewing ray of a view in \f$ C_0 \f$ and its Jacobians w.r.t. the pixel (6x2) and the
   * pose perturbation [dt; dtheta] of \f$ T_{0j} \f$ (6x6). */
  Vec6 viewRay(const TRayView& v, Eigen::Matrix<double, 6, 2>* J_L_uv = nullptr, Mat6* J_L_pose = nullptr) const;

 private:
  TRayClassifierParams m_p;
  camera::CCameraModel::Ptr m_cam;
  double m_lambda0 = 0;
  double m_medianChi2 = 0;           ///< median of chi-square with 3 dof (mapScale())
  geometry::TSignificance m_level;   ///< alpha with its chi-square critical values (computed once)
  std::vector<double> m_powerTable;  ///< powerAt() at lambda = i * kPowerStep
  std::vector<Vec3> m_directions;    ///< unit directions (half sphere) of detectionProbability()
};

/** CDF of the non-central chi-square distribution (Poisson mixture of central ones). */
double noncentralChi2Cdf(double x, int dof, double lambda);

/** The non-centrality \f$ \lambda \f$ at which a chi-square test with dof degrees of freedom at level
 * alpha rejects with probability `power`: \f$ P(\chi'^2_{dof}(\lambda) > \chi^2_{1-\alpha;dof}) = \f$ power
 * (e.g. 17.4 for alpha 0.05, power 0.95, 3 dof). */
double noncentralityForPower(double alpha, int dof, double power);
}  // namespace immslam::shadow
