/* Tests: MRPT scenes (named objects survive save/load, inverse-depth and XYZ ellipsoids drawn where
 * and as large as they should be, frustum field of view), offscreen PNG snapshots. */
#include <gtest/gtest.h>
#include <immslam/math/bearing.h>
#include <immslam/math/quaternion.h>
#include <immslam/viz/mrpt_conversions.h>
#include <immslam/viz/scene.h>
#include <immslam/viz/scene_render.h>

#include <mrpt/opengl/CEllipsoid3D.h>
#include <mrpt/opengl/CEllipsoidInverseDepth3D.h>
#include <mrpt/opengl/CFrustum.h>
#include <mrpt/opengl/CPointCloudColoured.h>
#include <mrpt/opengl/CSetOfLines.h>
#include <mrpt/opengl/CSetOfObjects.h>
#include <mrpt/opengl/CText.h>

#include <Eigen/Dense>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <filesystem>
#include <random>

using namespace immslam;
using namespace immslam::viz;
namespace mo = mrpt::opengl;

namespace
{
/** Where the tests leave their files (kept for inspection). */
std::string outDir()
{
  const std::string d = std::string(IMMSLAM_BINARY_DIR) + "/viz_test_output";
  std::filesystem::create_directories(d);
  return d;
}

/** Exposes MRPT's own parameter-space transform and generated surface of an inverse-depth
 * ellipsoid (protected members) so the tests check what MRPT really draws. */
class CProbeIdEllipsoid : public mo::CEllipsoidInverseDepth3D
{
 public:
  explicit CProbeIdEllipsoid(const mo::CEllipsoidInverseDepth3D& o)
      : mo::CRenderizable(o),
        mo::CRenderizableShaderTriangles(o),
        mo::CRenderizableShaderWireFrame(o),
        mo::CEllipsoidInverseDepth3D(o)
  {
  }
  Vec3 mean() const { return Vec3(m_mean[0], m_mean[1], m_mean[2]); }
  /** MRPT's map (inv_range, yaw, pitch) -> object-frame point. */
  Vec3 toLocal(const Vec3& param) const
  {
    std::vector<array_parameter_t> in(1);
    for (int k = 0; k < 3; ++k) in[0][k] = static_cast<float>(param[k]);
    std::vector<array_point_t> out;
    transformFromParameterSpace(in, out);
    return Vec3(out[0][0], out[0][1], out[0][2]);
  }
  /** The surface points MRPT renders, in the object frame. */
  std::vector<Vec3> surface() const
  {
    renderUpdateBuffers();
    std::vector<Vec3> pts;
    for (const auto& p : m_render_pts) pts.emplace_back(p[0], p[1], p[2]);
    return pts;
  }
};

/** Same for CEllipsoid3D (identity parameter transform). */
class CProbeEllipsoid : public mo::CEllipsoid3D
{
 public:
  std::vector<Vec3> surface() const
  {
    renderUpdateBuffers();
    std::vector<Vec3> pts;
    for (const auto& p : m_render_pts) pts.emplace_back(p[0], p[1], p[2]);
    return pts;
  }
};

Vec3 toVec(const mrpt::math::TPoint3D& p) { return Vec3(p.x, p.y, p.z); }

mrpt::math::CMatrixDouble33 toMrpt(const Mat3& m)
{
  mrpt::math::CMatrixDouble33 o;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) o(r, c) = m(r, c);
  return o;
}

/** A pose looking along direction `fwd` (optical z) from p, with y roughly down. */
core::TStampedPose lookingAlong(const Vec3& p, const Vec3& fwd, double t = 0)
{
  const Vec3 z = fwd.normalized();
  Vec3 x = Vec3::UnitY().cross(z);
  x.normalize();
  const Vec3 y = z.cross(x);
  Mat3 R;
  R << x, y, z;
  core::TStampedPose pose;
  pose.timestamp = t;
  pose.p_W_C = p;
  pose.q_W_C = math::fromEigen(Eigen::Quaterniond(R));
  return pose;
}

Mat3 randomSpd(std::mt19937& rng, double scale)
{
  std::normal_distribution<double> n;
  Mat3 A;
  for (int i = 0; i < 9; ++i) A(i) = n(rng);
  return scale * (A * A.transpose() + 0.2 * Mat3::Identity());
}

/** A content with every kind of object. */
TSceneContent fullContent()
{
  TSceneContent c;
  for (int k = 0; k < 20; ++k)
  {
    const double t = k / 19.0;
    c.trajectory.push_back(lookingAlong(Vec3(0.5 * t, 0.02 * std::sin(6 * t), 0.3 * t),
        Vec3(0.1 * t, 0, 1), k * 0.033));
  }
  std::vector<core::TStampedPose> gt = c.trajectory;
  for (auto& p : gt) p.p_W_C += Vec3(0.02, 0.0, -0.01);
  c.groundTruth = gt;
  c.smoothed.assign(c.trajectory.begin(), c.trajectory.begin() + 12);  // published up to frame 11
  for (auto& p : c.smoothed) p.p_W_C += Vec3(0.0, 0.01, 0.0);
  c.camera = camera::makeCameraModel("pinhole", 320, 240, {200, 200, 159.5, 119.5});
  std::mt19937 rng(3);
  for (int i = 0; i < 3; ++i)  // XYZ features
  {
    TMapPointView f;
    f.id = 10 + i;
    f.p_W = Vec3(-0.4 + 0.4 * i, -0.2 + 0.1 * i, 1.5 + 0.2 * i);
    f.cov_W = randomSpd(rng, 1e-3);
    c.points.push_back(f);
  }
  for (int i = 0; i < 4; ++i)  // inverse-depth features, two with a depth, two without
  {
    TMapPointView f;
    f.id = 20 + i;
    TInverseDepthView d;
    d.anchor_W = Vec3(0.05 * i, 0, 0);
    d.theta = -0.3 + 0.2 * i;
    d.phi = 0.1 - 0.05 * i;
    const bool known = i < 2;
    d.rho = known ? 0.8 : 0.05;
    d.cov_tpr = Vec3(1e-4, 1e-4, known ? 1e-3 : 0.25).asDiagonal();
    d.cov_tpr(0, 1) = d.cov_tpr(1, 0) = 3e-5;
    f.depthKnown = known;
    f.inverseDepth = d;
    f.p_W = d.anchor_W + math::Bearing::DirectionFromAngles(d.theta, d.phi) / d.rho;
    c.points.push_back(f);
  }
  for (int i = 0; i < 2; ++i)
  {
    TTrackView t;
    t.id = 100 + i;
    for (int k = 0; k < 8; ++k) t.polyline_W.push_back(Vec3(-0.5 + 0.1 * k, 0.2 * i, 2.0 + 0.05 * k));
    t.cls = i == 0 ? ETrackClass::Dynamic : ETrackClass::Pending;
    c.tracks.push_back(t);
  }
  c.title = "viz test scene";
  return c;
}

template <class T>
std::shared_ptr<T> get(const mo::COpenGLScene& s, const std::string& name)
{
  auto o = findObject(s, name);
  EXPECT_TRUE(o) << "no object named " << name;
  auto t = std::dynamic_pointer_cast<T>(o);
  EXPECT_TRUE(t) << name << " has class " << (o ? o->GetRuntimeClass()->className : "-");
  return t;
}

/** The pose of a named object in the world group's frame W (composing its parents). */
bool poseInWorld(const mo::CRenderizable::Ptr& node, const mo::CRenderizable::Ptr& target,
    const mrpt::poses::CPose3D& parent, mrpt::poses::CPose3D& out)
{
  const mrpt::poses::CPose3D p = parent + node->getPoseRef();
  if (node == target)
  {
    out = p;
    return true;
  }
  if (auto g = std::dynamic_pointer_cast<mo::CSetOfObjects>(node))
    for (const auto& ch : *g)
      if (poseInWorld(ch, target, p, out)) return true;
  return false;
}

mrpt::poses::CPose3D worldPoseOf(const mo::COpenGLScene& s, const std::string& name)
{
  auto world = findObject(s, "world");
  auto target = findObject(s, name);
  mrpt::poses::CPose3D out;
  EXPECT_TRUE(world && target && poseInWorld(world, target, -world->getPoseRef(), out)) << name;
  // The search started at world's pose composed with its inverse: `out` is relative to W.
  return out;
}
}  // namespace

TEST(VizScene, SaveLoadKeepsNamedObjectsAndCounts)
{
  const TSceneContent c = fullContent();
  const auto built = buildScene(c);
  const std::string path = outDir() + "/full.3Dscene";
  saveSceneFile(*built, path);
  ASSERT_TRUE(std::filesystem::file_size(path) > 1000);
  const auto s = loadSceneFile(path);

  for (const char* n : {"world", "grid", "origin", "trajectory", "gt_trajectory", "smoothed_trajectory", "camera",
           "camera_frustum", "camera_axes", "map", "map_xyz", "map_id_points", "map_rays", "tracks",
           "title"})
    EXPECT_TRUE(findObject(*s, n)) << n;
  EXPECT_EQ(get<mo::CSetOfLines>(*s, "trajectory")->getLineCount(), 19u);
  EXPECT_EQ(get<mo::CSetOfLines>(*s, "gt_trajectory")->getLineCount(), 19u);
  EXPECT_EQ(get<mo::CSetOfLines>(*s, "smoothed_trajectory")->getLineCount(), 11u);
  EXPECT_EQ(get<mo::CPointCloudColoured>(*s, "map_xyz")->size(), 3u);
  EXPECT_EQ(get<mo::CPointCloudColoured>(*s, "map_id_points")->size(), 2u);
  EXPECT_EQ(get<mo::CSetOfLines>(*s, "map_rays")->getLineCount(), 2u);
  EXPECT_TRUE(get<mo::CFrustum>(*s, "camera_frustum"));
  EXPECT_EQ(get<mo::CText>(*s, "title")->getString(), "viz test scene");

  // Per-feature ellipsoids: "map_xyz_<id>" for XYZ, "map_id_<id>" for inverse depth.
  size_t nXyz = 0, nId = 0;
  for (const auto& o : findObjectsByPrefix(*s, "map_xyz_"))
    nXyz += std::dynamic_pointer_cast<mo::CEllipsoid3D>(o) ? 1 : 0;
  for (const auto& o : findObjectsByPrefix(*s, "map_id_"))
    nId += std::dynamic_pointer_cast<mo::CEllipsoidInverseDepth3D>(o) ? 1 : 0;
  EXPECT_EQ(nXyz, 3u);
  EXPECT_EQ(nId, 4u);
  for (int id : {10, 11, 12}) EXPECT_TRUE(findObject(*s, "map_xyz_" + std::to_string(id))) << id;
  for (int id : {20, 21, 22, 23}) EXPECT_TRUE(findObject(*s, "map_id_" + std::to_string(id))) << id;

  // Tracks: one group each, a polyline and the last position.
  for (int id : {100, 101})
  {
    const std::string n = "track_" + std::to_string(id);
    EXPECT_TRUE(get<mo::CSetOfObjects>(*s, n));
    EXPECT_EQ(get<mo::CSetOfLines>(*s, n + "_line")->getLineCount(), 7u);
    const auto last = get<mo::CPointCloudColoured>(*s, n + "_last");
    ASSERT_EQ(last->size(), 1u);
    EXPECT_NEAR(last->getPoint3Df(0).x, c.tracks[id - 100].polyline_W.back().x(), 1e-6);
  }
  EXPECT_EQ(findObjectsByPrefix(*s, "track_").size(), 6u);  // 2 groups x (group, line, last)
}

TEST(VizScene, OptionalPartsAreLeftOut)
{
  TSceneContent c;
  c.trajectory.push_back(core::TStampedPose());
  TSceneOptions o;
  o.showGrid = false;
  o.showOriginAxes = false;
  const auto s = buildScene(c, o);
  EXPECT_FALSE(findObject(*s, "grid"));
  EXPECT_FALSE(findObject(*s, "origin"));
  EXPECT_FALSE(findObject(*s, "gt_trajectory"));
  EXPECT_FALSE(findObject(*s, "smoothed_trajectory"));
  EXPECT_FALSE(findObject(*s, "title"));
  EXPECT_TRUE(findObject(*s, "camera"));  // defaults to the last trajectory pose
  EXPECT_EQ(get<mo::CSetOfLines>(*s, "trajectory")->getLineCount(), 0u);
  EXPECT_TRUE(findObjectsByPrefix(*s, "track_").empty());
}

TEST(VizScene, ErrorsNameTheirCause)
{
  TSceneOptions o;
  o.nSigmas = -1;
  try
  {
    buildScene(TSceneContent(), o);
    FAIL();
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find("nSigmas"), std::string::npos);
  }
  const std::string bad = outDir() + "/no_such_dir/x.3Dscene";
  try
  {
    saveSceneFile(*buildScene(TSceneContent()), bad);
    FAIL();
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
  }
  try
  {
    loadSceneFile(bad);
    FAIL();
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
  }
}

TEST(VizScene, WorldGroupMapsOpticalWorldToZUp)
{
  const auto s = buildScene(fullContent());
  const auto world = findObject(*s, "world");
  ASSERT_TRUE(world);
  const auto& P = world->getPoseRef();
  // W's z (forward of the first camera) -> display x; W's y (down) -> display -z; W's x -> -y.
  EXPECT_LT((toVec(P.composePoint(mrpt::math::TPoint3D(0, 0, 1))) - Vec3(1, 0, 0)).norm(), 1e-12);
  EXPECT_LT((toVec(P.composePoint(mrpt::math::TPoint3D(0, 1, 0))) - Vec3(0, 0, -1)).norm(), 1e-12);
  EXPECT_LT((toVec(P.composePoint(mrpt::math::TPoint3D(1, 0, 0))) - Vec3(0, -1, 0)).norm(), 1e-12);
  // The same rotation as the conventions' CPose3D(0,0,0,-90deg,0,-90deg).
  const mrpt::poses::CPose3D ref(0, 0, 0, -M_PI / 2, 0, -M_PI / 2);
  EXPECT_LT((P.getRotationMatrix() - ref.getRotationMatrix()).asEigen().norm(), 1e-12);
}

TEST(VizScene, InverseDepthEllipsoidSitsOnTheFeature)
{
  // A feature at known depth with small uncertainty, seen from a rotated, translated anchor.
  TSceneContent c;
  TMapPointView f;
  f.id = 7;
  TInverseDepthView d;
  d.anchor_W = Vec3(0.3, -0.2, 0.5);
  d.theta = 0.4;
  d.phi = -0.25;
  d.rho = 0.5;
  d.cov_tpr = Vec3(1e-6, 2e-6, 1e-6).asDiagonal();
  d.cov_tpr(0, 2) = d.cov_tpr(2, 0) = 5e-7;
  f.inverseDepth = d;
  const Vec3 m = math::Bearing::DirectionFromAngles(d.theta, d.phi);
  const Vec3 expected = d.anchor_W + m / d.rho;
  f.p_W = expected;
  c.points.push_back(f);
  const std::string path = outDir() + "/one_id.3Dscene";
  saveSceneFile(*buildScene(c), path);
  const auto s = loadSceneFile(path);
  const auto e = get<mo::CEllipsoidInverseDepth3D>(*s, "map_id_7");
  ASSERT_TRUE(e);
  const mrpt::poses::CPose3D pose = worldPoseOf(*s, "map_id_7");

  CProbeIdEllipsoid probe(*e);
  EXPECT_LT((probe.mean() - Vec3(d.rho, d.theta, d.phi)).norm(), 1e-12);
  const Vec3 local = probe.toLocal(probe.mean());
  const Vec3 meanW = toVec(pose.composePoint(mrpt::math::TPoint3D(local.x(), local.y(), local.z())));
  EXPECT_LT((meanW - expected).norm(), 1e-5 * expected.norm()) << meanW.transpose();

  // Every surface point MRPT draws is close to the feature (3 sigma of a tiny covariance).
  double worst = 0;
  for (const Vec3& p : probe.surface())
    worst = std::max(worst,
        (toVec(pose.composePoint(mrpt::math::TPoint3D(p.x(), p.y(), p.z()))) - expected).norm());
  EXPECT_LT(worst, 0.05);
  EXPECT_GT(worst, 1e-4);
}

TEST(VizScene, EllipsoidSurfacesAreTheCovarianceIsoSurfaces)
{
  std::mt19937 rng(11);
  const double q = 2.0;
  for (int trial = 0; trial < 5; ++trial)
  {
    const Mat3 C = randomSpd(rng, 0.01);
    const Mat3 Ci = C.inverse();
    // CEllipsoid3D with the compensated matrix: (x^T C^-1 x) = q^2 on every drawn vertex.
    CProbeEllipsoid e;
    e.setCovMatrix(toMrpt(mrptEllipsoidCovariance(C)));
    e.setQuantiles(static_cast<float>(q));
    double lo = 1e9, hi = 0;
    for (const Vec3& p : e.surface())
    {
      const double m2 = p.dot(Ci * p);
      lo = std::min(lo, m2);
      hi = std::max(hi, m2);
    }
    EXPECT_NEAR(lo, q * q, 1e-3 * q * q) << "trial " << trial;
    EXPECT_NEAR(hi, q * q, 1e-3 * q * q) << "trial " << trial;
  }
  // Documents the MRPT 2.5.8 behaviour the compensation exists for: passing a correlated C itself
  // draws another ellipsoid (U U^T instead of U^T U). If this ever fails, MRPT fixed it and
  // mrptEllipsoidCovariance() should become the identity.
  Mat3 C;
  C << 4, 1.8, 0, 1.8, 1, 0.5, 0, 0.5, 1;
  const Mat3 Ci = C.inverse();
  CProbeEllipsoid raw;
  raw.setCovMatrix(toMrpt(C));
  raw.setQuantiles(1.0f);
  double rawDev = 0;
  for (const Vec3& p : raw.surface()) rawDev = std::max(rawDev, std::abs(p.dot(Ci * p) - 1.0));
  EXPECT_GT(rawDev, 1.0);
}

TEST(VizScene, InverseDepthSurfaceMatchesThetaPhiRhoCovariance)
{
  // Map the drawn surface back to (theta, phi, rho) and check the Mahalanobis distance.
  TInverseDepthView d;
  d.anchor_W = Vec3(0.1, 0.2, -0.3);
  d.theta = -0.2;
  d.phi = 0.3;
  d.rho = 1.0;
  d.cov_tpr << 4e-4, 1e-4, 2e-4,  //
      1e-4, 3e-4, -1e-4,           //
      2e-4, -1e-4, 9e-4;
  const TMrptInverseDepth mp = inverseDepthToMrpt(d);
  CProbeIdEllipsoid probe{mo::CEllipsoidInverseDepth3D()};
  mrpt::math::CMatrixDouble31 mean;
  for (int k = 0; k < 3; ++k) mean[k] = mp.mean[k];
  probe.setCovMatrixAndMean(toMrpt(mrptEllipsoidCovariance(mp.cov)), mean);
  probe.setQuantiles(3.0f);
  const Mat3 Ci = d.cov_tpr.inverse();
  double worst = 0;
  for (const Vec3& p : probe.surface())
  {
    const Vec3 pw = toVec(mp.pose.composePoint(mrpt::math::TPoint3D(p.x(), p.y(), p.z())));
    const Vec3 v = pw - d.anchor_W;
    const Vec2 tp = math::Bearing::AzimuthElevation(v);
    const Vec3 e(tp[0] - d.theta, tp[1] - d.phi, 1.0 / v.norm() - d.rho);
    worst = std::max(worst, std::abs(e.dot(Ci * e) - 9.0));
  }
  EXPECT_LT(worst, 0.05);  // float precision of MRPT's vertices
}

TEST(VizScene, UnknownDepthFeaturesAreRays)
{
  TSceneContent c;
  TMapPointView f;
  f.id = 3;
  f.depthKnown = false;
  TInverseDepthView d;
  d.theta = 0.1;
  d.phi = 0.05;
  d.rho = 0.05;
  d.cov_tpr = Vec3(1e-4, 1e-4, 0.25).asDiagonal();
  f.inverseDepth = d;
  c.points.push_back(f);
  c.trajectory.push_back(core::TStampedPose());
  TSceneOptions o;
  o.rayLength = 7.0;
  o.underflowRange = 70.0;
  const auto s = buildScene(c, o);
  const auto e = get<mo::CEllipsoidInverseDepth3D>(*s, "map_id_3");
  ASSERT_TRUE(e);
  EXPECT_FLOAT_EQ(e->getUnderflowMaxRange(), 70.0f);
  const Vec3 m = math::Bearing::DirectionFromAngles(d.theta, d.phi);
  // MRPT sends the surface points with negative inverse depth to the underflow range: a long cone.
  CProbeIdEllipsoid probe(*e);
  int far = 0;
  for (const Vec3& p : probe.surface())
  {
    const Vec3 pw = toVec(e->getPoseRef().composePoint(mrpt::math::TPoint3D(p.x(), p.y(), p.z())));
    if (std::abs(pw.norm() - 70.0) < 1e-2)
    {
      ++far;
      EXPECT_GT(pw.normalized().dot(m), 0.99);
    }
  }
  EXPECT_GT(far, 10);
  // And the explicit ray runs along m from the nearest allowed depth 1/(rho + 3 sigma) to 7.
  const auto rays = get<mo::CSetOfLines>(*s, "map_rays");
  ASSERT_EQ(rays->getLineCount(), 1u);
  const auto& seg = *rays->begin();
  EXPECT_LT((toVec(seg.point1) - m / (0.05 + 3 * 0.5)).norm(), 1e-9);
  EXPECT_LT((toVec(seg.point2) - 7.0 * m).norm(), 1e-9);
  EXPECT_EQ(get<mo::CPointCloudColoured>(*s, "map_id_points")->size(), 0u);
}

TEST(VizScene, FrustumUsesTheCameraFieldOfViewAndLooksForward)
{
  TSceneContent c;
  c.camera = camera::makeCameraModel("pinhole", 320, 240, {200, 180, 100.0, 119.5});
  c.currentCamera = lookingAlong(Vec3(1, 2, 3), Vec3(1, 0, 1));
  TSceneOptions o;
  o.frustumDepth = 0.5;
  const auto s = buildScene(c, o);
  const auto fr = get<mo::CFrustum>(*s, "camera_frustum");
  ASSERT_TRUE(fr);
  const double toDeg = 180.0 / M_PI;
  // Image right of the principal point (u up to 319.5) is CFrustum's "left" (its -Y side).
  EXPECT_NEAR(fr->getHorzFOVLeft(), std::atan(219.5 / 200) * toDeg, 1e-3);
  EXPECT_NEAR(fr->getHorzFOVRight(), std::atan(100.5 / 200) * toDeg, 1e-3);
  EXPECT_NEAR(fr->getVertFOVDown(), std::atan(120.0 / 180) * toDeg, 1e-3);
  EXPECT_NEAR(fr->getVertFOVUp(), std::atan(120.0 / 180) * toDeg, 1e-3);
  EXPECT_FLOAT_EQ(fr->getFarPlaneDistance(), 0.5f);
  // The frustum axis (+X of the object) is the camera's optical axis in W; its -Y is image right.
  const mrpt::poses::CPose3D P = worldPoseOf(*s, "camera_frustum");
  const Mat3 R = math::quatToRotation(c.currentCamera->q_W_C);
  EXPECT_LT((toVec(P.composePoint(mrpt::math::TPoint3D(1, 0, 0))) -
                (c.currentCamera->p_W_C + R.col(2)))
                .norm(),
      1e-9);
  EXPECT_LT((toVec(P.composePoint(mrpt::math::TPoint3D(0, -1, 0))) -
                (c.currentCamera->p_W_C + R.col(0)))
                .norm(),
      1e-9);
  EXPECT_LT((toVec(P.composePoint(mrpt::math::TPoint3D(0, 0, -1))) -
                (c.currentCamera->p_W_C + R.col(1)))
                .norm(),
      1e-9);
}

TEST(VizScene, ContentBoxesCoverTheContent)
{
  const TSceneContent c = fullContent();
  const TBox3 b = contentBox(c);
  ASSERT_FALSE(b.empty());
  for (const auto& p : c.trajectory)
    EXPECT_TRUE((p.p_W_C.array() >= b.min.array()).all() && (p.p_W_C.array() <= b.max.array()).all());
  // The scene's box (display frame) contains the display image of every content point and the rays.
  const auto s = buildScene(c);
  const TBox3 sb = sceneContentBox(*s);
  const auto D = displayFromWorld();
  for (const auto& f : c.points)
  {
    if (!f.depthKnown) continue;
    const Vec3 q = toVec(D.composePoint(mrpt::math::TPoint3D(f.p_W.x(), f.p_W.y(), f.p_W.z())));
    EXPECT_TRUE((q.array() >= sb.min.array() - 1e-6).all() && (q.array() <= sb.max.array() + 1e-6).all())
        << f.id;
  }
  EXPECT_GT(sb.diagonal(), b.diagonal());  // rays reach further than the content
}

TEST(VizRender, OffscreenSnapshotsHaveContent)
{
  std::string why;
  if (!offscreenRenderingAvailable(&why)) GTEST_SKIP() << why;
  const auto s = buildScene(fullContent());
  for (EView v : {EView::ThreeQuarter, EView::Top})
  {
    TRenderOptions o;
    o.view = v;
    o.caption = v == EView::Top ? "top view" : "three-quarter view";
    const std::string png =
        outDir() + (v == EView::Top ? "/scene_top.png" : "/scene_three_quarter.png");
    ASSERT_TRUE(renderScenePng(*s, png, 640, 480, o, &why)) << png << ": " << why;
    const cv::Mat img = cv::imread(png, cv::IMREAD_COLOR);
    ASSERT_FALSE(img.empty());
    EXPECT_EQ(img.cols, 640);
    EXPECT_EQ(img.rows, 480);
    // Non-background pixels, and some of the trajectory's dark blue.
    int nonWhite = 0, blue = 0;
    for (int r = 0; r < img.rows; ++r)
      for (int col = 0; col < img.cols; ++col)
      {
        const cv::Vec3b p = img.at<cv::Vec3b>(r, col);
        if (p[0] < 245 || p[1] < 245 || p[2] < 245) ++nonWhite;
        if (p[0] > 150 && p[1] < 110 && p[2] < 80) ++blue;
      }
    EXPECT_GT(nonWhite, 2000) << png;
    EXPECT_GT(blue, 10) << png;
  }
}

TEST(VizRender, BadSizeThrows)
{
  cv::Mat out;
  EXPECT_THROW(renderScene(*buildScene(TSceneContent()), 0, 10, TRenderOptions(), out),
      std::runtime_error);
}

TEST(VizRender, PaperLikeRaysAndEllipsoids)
{
  // IMM paper Fig. 3: after a rotation-only start every feature is a ray from the camera centre;
  // after translating, features get a depth and an ellipsoid.
  std::string why;
  if (!offscreenRenderingAvailable(&why)) GTEST_SKIP() << why;
  for (int stage = 0; stage < 2; ++stage)
  {
    TSceneContent c;
    c.camera = camera::makeCameraModel("pinhole", 320, 240, {200, 200, 159.5, 119.5});
    const int nPoses = stage == 0 ? 60 : 200;
    for (int k = 0; k < nPoses; ++k)
    {
      const double yaw = 0.5 * std::sin(k * 0.05);
      const Vec3 p = stage == 0 ? Vec3::Zero() : Vec3(0.006 * std::max(0, k - 60), 0, 0.002 * std::max(0, k - 60));
      c.trajectory.push_back(lookingAlong(p, Vec3(std::sin(yaw), 0, std::cos(yaw)), k / 30.0));
    }
    std::mt19937 rng(2);
    std::uniform_real_distribution<double> u(-1, 1);
    for (int i = 0; i < 30; ++i)
    {
      TMapPointView f;
      f.id = i;
      TInverseDepthView d;
      d.theta = 0.9 * u(rng);
      d.phi = 0.3 * u(rng);
      const double depth = 2.0 + 1.5 * (0.5 + 0.5 * u(rng));
      if (stage == 0)
      {
        d.rho = 0.3 + 0.2 * u(rng);
        d.cov_tpr = Vec3(2e-5, 2e-5, 0.25).asDiagonal();
        f.depthKnown = false;
      }
      else
      {
        d.rho = 1.0 / depth;
        const double sr = 0.03 * d.rho;
        d.cov_tpr = Vec3(2e-5, 2e-5, sr * sr).asDiagonal();
        f.depthKnown = true;
      }
      f.inverseDepth = d;
      f.p_W = d.anchor_W + math::Bearing::DirectionFromAngles(d.theta, d.phi) / d.rho;
      c.points.push_back(f);
    }
    c.title = stage == 0 ? "rotation only: no depths (rays)" : "after translation: depths estimated";
    const auto s = buildScene(c);
    for (EView v : {EView::ThreeQuarter, EView::Top})
    {
      TRenderOptions o;
      o.view = v;
      const std::string png = outDir() + "/paper_stage" + std::to_string(stage) +
                              (v == EView::Top ? "_top.png" : "_three_quarter.png");
      ASSERT_TRUE(renderScenePng(*s, png, 800, 600, o, &why)) << png << ": " << why;
    }
  }
}

TEST(VizRenderDeathTest, UnavailableRenderingReturnsFalseWithAReason)
{
  // In a fresh child process (the "threadsafe" style re-runs this binary), hide every EGL vendor:
  // rendering must report the failure, not crash or throw.
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  const auto scene = buildScene(fullContent());
  EXPECT_EXIT(
      {
        setenv("__EGL_VENDOR_LIBRARY_DIRS", "/nonexistent-egl-vendors", 1);
        std::string why;
        cv::Mat img;
        const bool ok = renderScene(*scene, 64, 48, TRenderOptions(), img, &why);
        std::cerr << "reason: " << why << std::endl;
        std::exit(ok ? 1 : 0);
      },
      testing::ExitedWithCode(0), "reason: offscreen EGL rendering unavailable");
}

TEST(VizRender, EllipsoidSurfacesWidenTheFittedBox)
{
  TSceneContent c;
  TMapPointView f;
  f.id = 1;
  f.p_W = Vec3(0, 0, 2);
  f.cov_W = Vec3(0.04, 0.01, 0.01).asDiagonal();  // 3 sigma = 0.6 along x
  c.points.push_back(f);
  c.trajectory.push_back(core::TStampedPose());
  TSceneOptions o;
  o.showOriginAxes = false;
  const auto s = buildScene(c, o);
  const TBox3 a = sceneContentBox(*s, false), b = sceneContentBox(*s, true);
  // W x is the display's -y: the ellipsoid reaches display y = -/+0.6 around the point.
  EXPECT_LT(b.min.y(), a.min.y() - 0.5);
  EXPECT_NEAR(b.min.y(), -0.6, 0.05);
  EXPECT_NEAR(b.max.y(), 0.6, 0.05);
}
