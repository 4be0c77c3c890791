/* imm-monoslam — what the SLAM filter gives the shadow filter every frame, and what the shadow
 * filter gives back (MonoSLAMBOT paper, Fig. 1: camera pose in, promotions and tracks out). */
#pragma once

#include <immslam/math/types.h>

#include <cstdint>
#include <string>
#include <vector>

namespace immslam::shadow
{
/** The camera's pose and its motion since the previous frame, from the SLAM filter, every frame.
 *
 * Perturbation conventions (doc/conventions.md; the same as eval::poseError6):
 * - pose: \f$ r = \hat r + \delta r \f$ (in W) and \f$ R_{WC} = \hat R_{WC}\,\mathrm{Exp}(\delta\theta) \f$
 *   (\f$ \delta\theta \f$ in C), cov_W_C is the covariance of \f$ [\delta r; \delta\theta] \f$;
 * - increment: the previous camera frame \f$ C_{k-1} \f$ sees the current one as
 *   \f$ p_{C_{k-1}} = R(dq)\, p_{C_k} + t \f$ (so t is the current camera centre in \f$ C_{k-1} \f$),
 *   with \f$ t = \hat t + \delta t \f$, \f$ R(dq) = R(\hat{dq})\,\mathrm{Exp}(\delta\theta) \f$ and
 *   cov_increment the covariance of \f$ [\delta t; \delta\theta] \f$.
 *
 * The classifier uses only the increments (relative motion): the absolute pose covariance mostly
 * describes a drift shared by all the views of a feature and would make the static/dynamic test far
 * too lenient (see CRayClassifier). The absolute pose only places dynamic tracks in W.
 *
 * Caveat for the producer: the classifier composes the increments of consecutive frames as
 * independent. In an EKF SLAM the errors of consecutive increments are correlated (through the
 * velocity estimate), so over many frames the composed covariance under-states the true relative
 * uncertainty. */
struct TCameraMotion
{
  double timestamp = 0;   ///< time of the current frame (s), copied into the report
  std::int64_t frame = 0; ///< index of the current frame
  double dt = 1;          ///< elapsed time since the previous frame, in nominal frame periods
  Vec3 r_W_C = Vec3::Zero();                   ///< current camera position in W
  Vec4 q_W_C = Vec4(1, 0, 0, 0);               ///< current camera orientation [qw qx qy qz]
  Mat6 cov_W_C = Mat6::Zero();                 ///< covariance of [dr; dtheta] of the pose
  Vec3 t = Vec3::Zero();                       ///< increment: current centre in C_{k-1}
  Vec4 dq = Vec4(1, 0, 0, 0);                  ///< increment: R(dq) = R_{C_{k-1} C_k}
  Mat6 cov_increment = Mat6::Zero();           ///< covariance of [dt; dtheta] of the increment
  /** Probability that the camera did not translate in this frame: the IMM bank's stationary and
   * rotation families (0 when unknown, e.g. a single general model). It weighs the power of the
   * depth-free test in a static decision (CRayClassifier). */
  double pNotTranslating = 0;
  /** The SLAM measured the camera in this frame. False while it has lost track (its pose is then the
   * motion models' prediction) and in the frame a relocalisation put it back on its map (the increment
   * then holds that jump, not the camera's motion). Without a measured motion the classifier neither
   * tests nor decides, and every pending feature's views start again at its next measurement: the
   * relative poses across the gap are not known (CShadowFilter). */
  bool measured = true;

  /** The motion of a camera that moved from pose (r0, q0) to (r1, q1) (both T_W_C): t and dq of
   * the increment (covariances left zero). */
  static TCameraMotion FromPoses(const Vec3& r0, const Vec4& q0, const Vec3& r1, const Vec4& q1);
};

/** Class of a shadow feature. */
enum class EShadowClass
{
  Pending,  ///< not yet classified (held in the shadow filter)
  Static,   ///< classified static (promoted into the SLAM filter, then removed from the shadow filter)
  Dynamic   ///< classified dynamic (kept and tracked in the shadow filter)
};

/** "pending", "static", "dynamic" (the words of classifications.csv). */
std::string className(EShadowClass c);

/** One classification decision (a row of classifications.csv). */
struct TDecision
{
  std::int64_t id = -1;
  EShadowClass cls = EShadowClass::Pending;  ///< Static or Dynamic
  Vec2 uv = Vec2::Zero();                    ///< the feature's measured pixel in this frame
  double timestamp = 0;
  std::int64_t frame = 0;
  int ageFrames = 0;       ///< frames since the feature's first observation
  double testT = 0;        ///< the test statistic of the deciding frame (eq. 14)
  /** Static decisions: the test's detection probability for a point moving at the configured minimum
   * speed in a random direction, and the worst-direction detectable speed (px/frame) at the same
   * power (see CRayClassifier). */
  double detectionProbability = 0;
  double minDetectableVelocityPx = 0;
};

/** A static feature to insert into the SLAM filter now (it has been removed from the shadow filter).
 * rho is the inverse *distance* from the current camera centre (the inverse-depth parametrization's
 * rho, dimensionless like the SLAM's lengths), from the static triangulation of the classifier's
 * three rays (fallback: the shadow EKF's w). */
struct TPromotion
{
  std::int64_t id = -1;
  Vec2 uv = Vec2::Zero();       ///< measured pixel in the current frame
  double rho = 1;               ///< inverse distance from the current camera
  double sigmaRho = 1;          ///< its standard deviation (first order)
  Vec3 p_C = Vec3::Zero();      ///< the triangulated point in the current camera frame
  bool fromTriangulation = true;///< false: rho/sigmaRho are the shadow EKF's
};

/** A dynamic feature's estimate in this frame (a row of tracks.csv when measured). */
struct TTrackPoint
{
  std::int64_t id = -1;
  Vec3 p_W = Vec3::Zero();      ///< estimated world position (current SLAM pose o shadow state)
  Mat3 cov_W = Mat3::Identity();///< its covariance (shadow state + camera pose, first order)
  Vec3 v_W = Vec3::Zero();      ///< estimated velocity in W (length per frame)
  Vec2 uv = Vec2::Zero();       ///< measured pixel, or the prediction when not measured
  bool measured = false;        ///< found in this frame
  double inverseDistance = 0;   ///< the EKF's w (0: at infinity; p_W then uses w clamped)
  /** sigma_w / w: the relative 1-sigma of the distance (first order), from the EKF's own w (not
   * clamped, so large for a bearing of unknown depth, where cov_W is not meaningful in depth). */
  double distanceRelativeStd = 0;
};

/** Every shadow feature in this frame (for overlays). */
struct TFeatureView
{
  std::int64_t id = -1;
  EShadowClass cls = EShadowClass::Pending;  ///< Pending or Dynamic
  Vec2 uv = Vec2::Zero();       ///< measured pixel, or the prediction when not measured
  Vec2 predicted = Vec2::Zero();///< predicted pixel (eq. 5 through the camera model)
  Mat2 S = Mat2::Identity();    ///< innovation covariance of the search
  bool searched = false;        ///< predicted inside the image and searched
  bool measured = false;        ///< matched (and used in the update)
  double score = 0;             ///< ZNCC of the match against its template (0: not measured or not known)
  /** cls Dynamic without a decision: seen moving, its template following no point
   * (CShadowFilter::TOptions::min_point_ncc); shown and counted as undecided. */
  bool incoherent = false;
  int ageFrames = 0;
};

/** What happened in one frame. */
struct TShadowReport
{
  double timestamp = 0;
  std::int64_t frame = 0;
  std::vector<TDecision> decisions;    ///< classifications made in this frame
  std::vector<TPromotion> promotions;  ///< static features to move into SLAM now
  std::vector<TTrackPoint> tracks;     ///< every dynamic feature still tracked
  std::vector<TFeatureView> views;     ///< every shadow feature (after this frame's removals)
  int nPending = 0, nDynamic = 0;      ///< features held after the frame (undecided ones seen moving, TFeatureView::incoherent, count as pending)
  int nSearched = 0, nMeasured = 0;    ///< searches and matches of this frame
  int nPromoted = 0, nNewDynamic = 0;  ///< decisions of this frame
  int nTimedOut = 0;                   ///< pending features dropped undecided (max age)
  int nLost = 0;                       ///< pending features dropped after too many misses
  int nDynamicDropped = 0;             ///< dynamic features dropped after too many misses
  int nIncoherent = 0;                 ///< features found moving in this frame whose template follows no point (held, no decision)
  int nLone = 0;                       ///< features found moving in this frame while no other one nearby moves (held until one does)
  int nLoneDecided = 0;                ///< of nNewDynamic: features held alone before (nLone of an earlier frame)
  double timeMs = 0;                   ///< wall time of the frame
  double tPredictMs = 0, tSearchMs = 0, tUpdateMs = 0, tClassifyMs = 0;
};
}  // namespace immslam::shadow
