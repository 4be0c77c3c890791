/* imm-monoslam — MRPT 3-D scenes (.3Dscene, opened by SceneViewer3D) of a SLAM run.
 *
 * The content is plain data (TSceneContent); buildScene() turns it into an mrpt::opengl scene whose
 * objects are all named, so tests and tools can find and count them:
 *
 *   "world"            CSetOfObjects, pose T_D_W (see TSceneOptions::zUpDisplay); all below is in W
 *     "grid"           CGridPlaneXZ, a ground plane below the camera (W is y-down)
 *     "origin"         CSetOfObjects, axes of W (x red, y green, z blue)
 *     "trajectory"     CSetOfLines, estimated camera centres
 *     "gt_trajectory"  CSetOfLines, ground truth (when given)
 *     "smoothed_trajectory"  CSetOfLines, the keyframe smoother's trajectory (when given)
 *     "camera"         CSetOfObjects at the current pose: "camera_frustum" (CFrustum from the
 *                      camera's field of view) and "camera_axes" (optical frame axes)
 *     "map"            CSetOfObjects:
 *       "map_xyz"          CPointCloudColoured, features without inverse-depth data (one point each)
 *       "map_xyz_<id>"     CEllipsoid3D, their n-sigma uncertainty (cov_W)
 *       "map_id_<id>"      CEllipsoidInverseDepth3D, inverse-depth features at their anchor
 *       "map_id_points"    CPointCloudColoured, means of inverse-depth features with a depth
 *       "map_rays"         CSetOfLines, one ray per inverse-depth feature without a depth
 *     "tracks"         CSetOfObjects with one "track_<id>" CSetOfObjects per track, holding
 *                      "track_<id>_line" (CSetOfLines) and "track_<id>_last" (CPointCloudColoured)
 *     "title"          CText
 */
#pragma once

#include <immslam/camera/CCameraModel.h>
#include <immslam/core/TTrajectory.h>
#include <immslam/math/types.h>
#include <immslam/viz/colours.h>

#include <mrpt/opengl/COpenGLScene.h>

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace immslam::viz
{
/** An inverse-depth feature (doc/conventions.md): \f$ p_W = x_0 + m(\theta,\phi)/\rho \f$ with
 * \f$ m = (\cos\phi\sin\theta,\, -\sin\phi,\, \cos\phi\cos\theta) \f$ (angles in W). */
struct TInverseDepthView
{
  Vec3 anchor_W = Vec3::Zero();  ///< x0: camera centre when the feature was initialised
  double theta = 0;              ///< azimuth of the ray in W (rad)
  double phi = 0;                ///< elevation of the ray in W (rad)
  double rho = 1;                ///< inverse depth along the ray
  Mat3 cov_tpr = Mat3::Zero();   ///< covariance of (theta, phi, rho), in that order
};

/** One map feature as the viewer sees it. */
struct TMapPointView
{
  std::int64_t id = 0;     ///< feature id (names the scene objects)
  bool depthKnown = true;  ///< false: drawn as a ray (its inverse-depth interval contains 0)
  Vec3 p_W = Vec3::Zero(); ///< mean position (for inverse-depth features: x0 + m / rho)
  Mat3 cov_W = Mat3::Zero(); ///< XYZ covariance (or its Euclidean approximation); zero: none
  /** Inverse-depth data: when present the feature is drawn with CEllipsoidInverseDepth3D at its
   * anchor (the exact uncertainty shape, a ray when the depth is unknown), else as an XYZ point
   * with a CEllipsoid3D from cov_W. */
  std::optional<TInverseDepthView> inverseDepth;
};

/** Class of a feature tracked outside the SLAM map (MonoSLAMBOT shadow filter). */
enum class ETrackClass
{
  Dynamic,  ///< classified as moving (green)
  Static,   ///< classified as static (blue)
  Pending   ///< still waiting for a decision (red)
};

/** The trajectory of one tracked feature. */
struct TTrackView
{
  std::int64_t id = 0;                 ///< feature id (names the objects "track_<id>...")
  std::vector<Vec3> polyline_W;        ///< estimated positions in W, oldest first
  ETrackClass cls = ETrackClass::Dynamic;  ///< selects the colour unless `colour` is set
  std::optional<TColour> colour;       ///< overrides the class colour
};

/** Everything one scene shows. All poses and points are in the world frame W. */
struct TSceneContent
{
  std::vector<core::TStampedPose> trajectory;                 ///< estimated T_W_C over time
  std::optional<std::vector<core::TStampedPose>> groundTruth; ///< drawn when present (aligned to W)
  /** The online smoother's poses published so far (refine::CKeyframeSmoother), drawn beside the
   * filter's when it has two or more. */
  std::vector<core::TStampedPose> smoothed;
  /** The camera drawn as a frustum; defaults to trajectory.back() (none if both are empty). */
  std::optional<core::TStampedPose> currentCamera;
  camera::CCameraModel::Ptr camera;  ///< for the frustum's field of view (null: 60 x 45 deg)
  std::vector<TMapPointView> points; ///< map features
  std::vector<TTrackView> tracks;    ///< dynamic-feature tracks
  std::string title;                 ///< CText title (empty: none)
};

/** Appearance of the scene. Lengths in W units; 0 (or NaN) means "derived from the content". */
struct TSceneOptions
{
  /** If true the "world" group gets the pose CPose3D(0,0,0,-90deg,0,-90deg), which maps W (the
   * first camera's optical frame: x right, y down, z forward) onto MRPT's z-up convention (x
   * forward, y left, z up), so SceneViewer3D's orbiting and the top view behave naturally. */
  bool zUpDisplay = true;
  bool showGrid = true;          ///< ground grid in the XZ plane of W
  double gridY = std::numeric_limits<double>::quiet_NaN();  ///< grid height in W (NaN: below all)
  double gridSpacing = 0;        ///< grid cell size (0: about 1/10 of the content extent)
  bool showOriginAxes = true;    ///< axes of W at its origin
  double nSigmas = 3.0;          ///< ellipsoid size: sqrt of the chi-square quantile (3: 97 % in 3-D)
  int ellipsoidSegments = 16;    ///< slices/stacks of each ellipsoid mesh
  /** Length of the "map_rays" lines of features without a depth (0: 1.5 x the content extent,
   * at least 1). Snapshots fit these lines, not the ellipsoids' far ends. */
  double rayLength = 0;
  /** setUnderflowMaxRange() of every inverse-depth ellipsoid: where MRPT puts the surface points
   * with a negative inverse depth (0: 100 x rayLength). MRPT draws the points with a small positive
   * inverse depth at 1/inv_range, unbounded, so a finite underflow range would end the cone of an
   * unknown-depth feature at an arbitrary ring; a far one makes every such cone a ray to
   * "infinity" (beyond any snapshot's frame), as the papers draw them. */
  double underflowRange = 0;
  double frustumDepth = 0;       ///< far plane of the camera frustum (0: 8 % of the extent, >= 0.1)
  double axesLength = 0;         ///< length of the camera/origin axes (0: half the frustum depth)
  float pointSize = 5.0f;        ///< map point size (pixels)
  float trackPointSize = 10.0f;  ///< size of the last position of a track (pixels)
  float lineWidth = 2.0f;        ///< trajectory / track line width (pixels)
  TColour background = palette::kWhite;  ///< viewport background
  TColour trajectoryColour = palette::kTrajectory;  ///< estimated trajectory
  TColour groundTruthColour = palette::kGroundTruth; ///< ground truth
  TColour smoothedColour = palette::kSmoothed;       ///< the smoother's trajectory
  TColour cameraColour = palette::kCamera;          ///< current camera frustum
  TColour xyzColour = palette::kMapXyz;             ///< XYZ features and their ellipsoids
  TColour idKnownColour = palette::kMapIdKnown;     ///< inverse-depth features with a depth
  TColour idUnknownColour = palette::kMapIdUnknown; ///< rays of features without a depth
  TColour gridColour = palette::kGrid;              ///< grid lines
  TColour textColour = palette::kBlack;             ///< title
};

/** An axis-aligned box; empty until a point is added. */
struct TBox3
{
  Vec3 min = Vec3::Constant(std::numeric_limits<double>::infinity());   ///< lower corner
  Vec3 max = Vec3::Constant(-std::numeric_limits<double>::infinity());  ///< upper corner
  bool empty() const { return !(min.array() <= max.array()).all(); }
  void add(const Vec3& p);              ///< grows the box to contain p (ignores non-finite p)
  Vec3 centre() const { return 0.5 * (min + max); }
  double diagonal() const { return empty() ? 0.0 : (max - min).norm(); }
};

/** The box (in W) of what the scene shows at finite distance: trajectory, ground truth, current
 * camera, features with a depth, anchors of features without one, and tracks. */
TBox3 contentBox(const TSceneContent& content);

/** Options sized from the trajectory and the features with a known depth (not from unknown-depth
 * rays, which reach far): axes, frustum, ray length and grid follow the size of what was estimated. */
TSceneOptions sceneOptionsFitting(const TSceneContent& content);

/** Builds the scene described in this header's comment.
 * \throws std::runtime_error if an option is invalid (names it). Non-finite points are skipped;
 * ellipsoids are skipped for covariances that are not finite and positive definite. */
mrpt::opengl::COpenGLScene::Ptr buildScene(
    const TSceneContent& content, const TSceneOptions& options = TSceneOptions());

/** Writes a .3Dscene file (MRPT serialization; SceneViewer3D opens it).
 * \throws std::runtime_error naming the path if it cannot be written. */
void saveSceneFile(const mrpt::opengl::COpenGLScene& scene, const std::string& path);

/** Reads a .3Dscene file.
 * \throws std::runtime_error naming the path if it cannot be read or is not a scene. */
mrpt::opengl::COpenGLScene::Ptr loadSceneFile(const std::string& path);

/** Every object of the scene's main viewport (recursively through CSetOfObjects) whose name starts
 * with `prefix` ("" lists them all), in depth-first insertion order. */
std::vector<mrpt::opengl::CRenderizable::Ptr> findObjectsByPrefix(
    const mrpt::opengl::COpenGLScene& scene, const std::string& prefix);

/** The first object named exactly `name` (depth-first), or null. */
mrpt::opengl::CRenderizable::Ptr findObject(
    const mrpt::opengl::COpenGLScene& scene, const std::string& name);
}  // namespace immslam::viz
