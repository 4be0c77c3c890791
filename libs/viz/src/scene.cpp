/* imm-monoslam — MRPT scene of a SLAM run: trajectory, camera, map with uncertainty, tracks. */
#include <immslam/viz/mrpt_conversions.h>
#include <immslam/viz/scene.h>

#include <Eigen/Geometry>

#include <immslam/math/bearing.h>

#include <mrpt/opengl/CEllipsoid3D.h>
#include <mrpt/opengl/CEllipsoidInverseDepth3D.h>
#include <mrpt/opengl/CFrustum.h>
#include <mrpt/opengl/CGridPlaneXZ.h>
#include <mrpt/opengl/CPointCloudColoured.h>
#include <mrpt/opengl/CSetOfLines.h>
#include <mrpt/opengl/CSetOfObjects.h>
#include <mrpt/opengl/CText.h>
#include <mrpt/opengl/stock_objects.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>

namespace immslam::viz
{
namespace mo = mrpt::opengl;

void TBox3::add(const Vec3& p)
{
  if (!p.allFinite()) return;
  min = min.cwiseMin(p);
  max = max.cwiseMax(p);
}

TBox3 contentBox(const TSceneContent& c)
{
  TBox3 box;
  for (const auto& p : c.trajectory) box.add(p.p_W_C);
  if (c.groundTruth)
    for (const auto& p : *c.groundTruth) box.add(p.p_W_C);
  for (const auto& p : c.smoothed) box.add(p.p_W_C);
  if (c.currentCamera) box.add(c.currentCamera->p_W_C);
  for (const auto& f : c.points)
  {
    if (f.depthKnown)
      box.add(f.p_W);
    else if (f.inverseDepth)
      box.add(f.inverseDepth->anchor_W);
  }
  for (const auto& t : c.tracks)
    for (const auto& p : t.polyline_W) box.add(p);
  return box;
}

namespace
{
/** A "nice" number (1, 2 or 5 times a power of ten) close to x > 0. */
double niceNumber(double x)
{
  const double e = std::floor(std::log10(x));
  const double f = x / std::pow(10.0, e);
  const double nf = f < 1.5 ? 1 : (f < 3.5 ? 2 : (f < 7.5 ? 5 : 10));
  return nf * std::pow(10.0, e);
}

void requirePositiveFinite(double v, const char* key)
{
  if (!std::isfinite(v) || v < 0)
    throw std::runtime_error(std::string("viz::buildScene: option ") + key +
                             " must be finite and >= 0, got " + std::to_string(v));
}

mo::CSetOfLines::Ptr polyline(const std::vector<Vec3>& pts, const TColour& col, float width)
{
  auto lines = mo::CSetOfLines::Create();
  lines->setColor_u8(toMrptColour(col));
  lines->setLineWidth(width);
  // Wide lines are not available in every OpenGL profile (offscreen Mesa draws 1 px): dots at
  // the vertices keep dense polylines visible.
  lines->setVerticesPointSize(width + 1.0f);
  const Vec3* prev = nullptr;
  for (const auto& p : pts)
  {
    if (!p.allFinite()) continue;
    if (prev) lines->appendLine((*prev)[0], (*prev)[1], (*prev)[2], p[0], p[1], p[2]);
    prev = &p;
  }
  return lines;
}

std::vector<Vec3> positions(const std::vector<core::TStampedPose>& poses)
{
  std::vector<Vec3> out;
  out.reserve(poses.size());
  for (const auto& p : poses) out.push_back(p.p_W_C);
  return out;
}

/** Field of view of a camera model: (right, left, down, up) half-angles in degrees, from the
 * bearings of the image-border midpoints. */
std::array<double, 4> halfFovDeg(const camera::CCameraModel* cam)
{
  if (!cam) return {30.0, 30.0, 22.5, 22.5};
  const double W = cam->width(), H = cam->height();
  const auto ang = [](const Vec3& b, int axis) {
    return std::atan2(std::abs(b[axis]), b[2]) * 180.0 / M_PI;
  };
  const Vec3 bl = cam->unproject(Vec2(-0.5, cam->cy())).unitVector();
  const Vec3 br = cam->unproject(Vec2(W - 0.5, cam->cy())).unitVector();
  const Vec3 bt = cam->unproject(Vec2(cam->cx(), -0.5)).unitVector();
  const Vec3 bb = cam->unproject(Vec2(cam->cx(), H - 0.5)).unitVector();
  std::array<double, 4> out{ang(br, 0), ang(bl, 0), ang(bb, 1), ang(bt, 1)};
  for (auto& a : out)
    if (!std::isfinite(a) || a <= 0) a = 30.0;
  return out;
}

mo::CSetOfObjects::Ptr group(const std::string& name)
{
  auto g = mo::CSetOfObjects::Create();
  g->setName(name);
  return g;
}

mo::CSetOfObjects::Ptr cameraObject(
    const core::TStampedPose& pose, const camera::CCameraModel* cam, double depth, double axes,
    const TSceneOptions& o)
{
  auto g = group("camera");
  g->setPose(toMrptPose(pose));
  const auto fov = halfFovDeg(cam);
  auto fr = mo::CFrustum::Create();
  fr->setName("camera_frustum");
  // CFrustum's "left" half-angle spans its -Y side, which is the optical +x (image right) side;
  // its "down" half-angle spans -Z, the optical +y (image down) side.
  fr->setHorzFOVAsymmetric(static_cast<float>(fov[0]), static_cast<float>(fov[1]));
  fr->setVertFOVAsymmetric(static_cast<float>(fov[2]), static_cast<float>(fov[3]));
  fr->setNearFarPlanes(0.0f, static_cast<float>(depth));
  fr->setColor_u8(toMrptColour(o.cameraColour));
  fr->setLineWidth(o.lineWidth);
  fr->setPlaneColor(toMrptColour(o.cameraColour, 40));
  fr->setPose(opticalToMrptBody());
  g->insert(fr);
  auto ax = mo::stock_objects::CornerXYZSimple(static_cast<float>(axes), 2.0f);
  ax->setName("camera_axes");
  g->insert(ax);
  return g;
}

/** The uncertainty ellipsoid of an inverse-depth map point (MRPT's parametrization `mp`, its
 * covariance M in MRPT's ellipsoid order). */
mo::CRenderizable::Ptr inverseDepthEllipsoid(const TMrptInverseDepth& mp, const Mat3& M, const TColour& col,
    const std::string& id, double underflowRange, const TSceneOptions& o)
{
  auto e = mo::CEllipsoidInverseDepth3D::Create();
  e->setName("map_id_" + id);
  e->setPose(mp.pose);
  mrpt::math::CMatrixDouble33 cov;
  mrpt::math::CMatrixDouble31 mean;
  for (int r = 0; r < 3; ++r)
  {
    mean[r] = mp.mean[r];
    for (int k = 0; k < 3; ++k) cov(r, k) = M(r, k);
  }
  e->setCovMatrixAndMean(cov, mean);
  e->setQuantiles(static_cast<float>(o.nSigmas));
  e->setUnderflowMaxRange(static_cast<float>(underflowRange));
  e->setNumberOfSegments(static_cast<uint32_t>(std::max(4, o.ellipsoidSegments)));
  e->setColor_u8(toMrptColour(col, 200));
  e->setLineWidth(1.0f);
  return e;
}

/** The uncertainty ellipsoid of an XYZ map point at p_W (covariance M in MRPT's order). */
mo::CRenderizable::Ptr xyzEllipsoid(const Vec3& p_W, const Mat3& M, const std::string& id, const TSceneOptions& o)
{
  auto e = mo::CEllipsoid3D::Create();
  e->setName("map_xyz_" + id);
  e->setLocation(p_W[0], p_W[1], p_W[2]);
  mrpt::math::CMatrixDouble33 cov;
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k) cov(r, k) = M(r, k);
  e->setCovMatrix(cov);
  e->setQuantiles(static_cast<float>(o.nSigmas));
  e->setNumberOfSegments(static_cast<uint32_t>(std::max(4, o.ellipsoidSegments)));
  e->setColor_u8(toMrptColour(o.xyzColour, 200));
  e->setLineWidth(1.0f);
  return e;
}

void addMap(mo::CSetOfObjects& world, const TSceneContent& c, double rayLength,
    double underflowRange, const TSceneOptions& o)
{
  auto map = group("map");
  auto xyz = mo::CPointCloudColoured::Create();
  xyz->setName("map_xyz");
  xyz->setPointSize(o.pointSize);
  auto idPts = mo::CPointCloudColoured::Create();
  idPts->setName("map_id_points");
  idPts->setPointSize(o.pointSize);
  auto rays = mo::CSetOfLines::Create();
  rays->setName("map_rays");
  rays->setColor_u8(toMrptColour(o.idUnknownColour));
  rays->setLineWidth(std::max(1.0f, 0.5f * o.lineWidth));
  std::vector<mo::CRenderizable::Ptr> ellipsoids;
  const auto rgb = [](const TColour& k) {
    return std::array<float, 3>{k.r / 255.f, k.g / 255.f, k.b / 255.f};
  };
  const auto kx = rgb(o.xyzColour), kk = rgb(o.idKnownColour);
  for (const auto& f : c.points)
  {
    const std::string id = std::to_string(f.id);
    if (f.inverseDepth)
    {
      const TInverseDepthView& d = *f.inverseDepth;
      if (!d.anchor_W.allFinite() || !std::isfinite(d.theta) || !std::isfinite(d.phi) ||
          !std::isfinite(d.rho))
        continue;
      const Vec3 m = math::Bearing::DirectionFromAngles(d.theta, d.phi);
      const TColour col = f.depthKnown ? o.idKnownColour : o.idUnknownColour;
      const TMrptInverseDepth mp = inverseDepthToMrpt(d);
      const Mat3 M = mrptEllipsoidCovariance(mp.cov);
      if (!M.isZero(0)) ellipsoids.push_back(inverseDepthEllipsoid(mp, M, col, id, underflowRange, o));
      if (f.depthKnown)
      {
        const Vec3 p = d.rho > 0 ? Vec3(d.anchor_W + m / d.rho) : f.p_W;
        if (p.allFinite()) idPts->push_back(p[0], p[1], p[2], kk[0], kk[1], kk[2]);
      }
      else
      {
        // The paper draws features whose inverse-depth interval contains 0 as rays: from the
        // nearest depth the interval allows to the ray length.
        const double sr = std::sqrt(std::max(0.0, d.cov_tpr(2, 2)));
        const double rhoMax = d.rho + o.nSigmas * sr;
        const double near = rhoMax > 0 ? std::min(1.0 / rhoMax, rayLength) : 0.0;
        const Vec3 a = d.anchor_W + near * m, b = d.anchor_W + rayLength * m;
        rays->appendLine(a[0], a[1], a[2], b[0], b[1], b[2]);
      }
    }
    else
    {
      if (!f.p_W.allFinite()) continue;
      xyz->push_back(f.p_W[0], f.p_W[1], f.p_W[2], kx[0], kx[1], kx[2]);
      const Mat3 M = mrptEllipsoidCovariance(f.cov_W);
      if (M.isZero(0)) continue;
      ellipsoids.push_back(xyzEllipsoid(f.p_W, M, id, o));
    }
  }
  map->insert(xyz);
  map->insert(idPts);
  map->insert(rays);
  for (auto& e : ellipsoids) map->insert(e);
  world.insert(map);
}

void addTracks(mo::CSetOfObjects& world, const TSceneContent& c, const TSceneOptions& o)
{
  auto tracks = group("tracks");
  for (const auto& t : c.tracks)
  {
    const TColour col = t.colour ? *t.colour
                                 : (t.cls == ETrackClass::Dynamic
                                           ? palette::kDynamic
                                           : (t.cls == ETrackClass::Static ? palette::kStatic
                                                                           : palette::kPending));
    const std::string name = "track_" + std::to_string(t.id);
    auto g = group(name);
    auto line = polyline(t.polyline_W, col, o.lineWidth);
    line->setName(name + "_line");
    g->insert(line);
    auto last = mo::CPointCloudColoured::Create();
    last->setName(name + "_last");
    last->setPointSize(o.trackPointSize);
    for (auto it = t.polyline_W.rbegin(); it != t.polyline_W.rend(); ++it)
      if (it->allFinite())
      {
        last->push_back((*it)[0], (*it)[1], (*it)[2], col.r / 255.f, col.g / 255.f, col.b / 255.f);
        break;
      }
    g->insert(last);
    tracks->insert(g);
  }
  world.insert(tracks);
}

void collect(const mo::CRenderizable::Ptr& obj, const std::string& prefix,
    std::vector<mo::CRenderizable::Ptr>& out)
{
  if (!obj) return;
  if (obj->getName().compare(0, prefix.size(), prefix) == 0) out.push_back(obj);
  if (auto g = std::dynamic_pointer_cast<mo::CSetOfObjects>(obj))
    for (const auto& child : *g) collect(child, prefix, out);
}
/** The grid plane of buildScene(): under everything drawn at finite distance, rays included. */
mo::CRenderizable::Ptr gridPlane(const TSceneContent& c, const TBox3& box, double rayLength, const TSceneOptions& o)
{
  TBox3 g = box;
  for (const auto& f : c.points)
    if (!f.depthKnown && f.inverseDepth)
      g.add(f.inverseDepth->anchor_W +
            rayLength * math::Bearing::DirectionFromAngles(
                            f.inverseDepth->theta, f.inverseDepth->phi));
  const double gExtent = std::max(g.diagonal(), 1e-3);
  const double spacing = o.gridSpacing > 0 ? o.gridSpacing : niceNumber(gExtent / 10.0);
  const double y = std::isfinite(o.gridY) ? o.gridY : g.max.y() + 0.05 * gExtent;
  const auto lo = [&](double v) { return std::floor(v / spacing) * spacing; };
  const auto hi = [&](double v) { return std::ceil(v / spacing) * spacing; };
  auto grid = mo::CGridPlaneXZ::Create(static_cast<float>(lo(g.min.x())),
      static_cast<float>(hi(g.max.x())), static_cast<float>(lo(g.min.z())),
      static_cast<float>(hi(g.max.z())), static_cast<float>(y), static_cast<float>(spacing),
      1.0f, true);
  grid->setName("grid");
  grid->setColor_u8(toMrptColour(o.gridColour));
  return grid;
}

}  // namespace

mo::COpenGLScene::Ptr buildScene(const TSceneContent& c, const TSceneOptions& o)
{
  requirePositiveFinite(o.nSigmas, "nSigmas");
  requirePositiveFinite(o.rayLength, "rayLength");
  requirePositiveFinite(o.underflowRange, "underflowRange");
  requirePositiveFinite(o.frustumDepth, "frustumDepth");
  requirePositiveFinite(o.axesLength, "axesLength");
  requirePositiveFinite(o.gridSpacing, "gridSpacing");

  TBox3 box = contentBox(c);
  if (box.empty()) box.add(Vec3::Zero());
  box.add(Vec3::Zero());  // W's origin (the first camera) is always shown
  const double extent = std::max(box.diagonal(), 1e-3);
  const double rayLength = o.rayLength > 0 ? o.rayLength : std::max(1.0, 1.5 * extent);
  const double frustum = o.frustumDepth > 0 ? o.frustumDepth : std::max(0.1, 0.08 * extent);
  const double axes = o.axesLength > 0 ? o.axesLength : 0.5 * frustum;

  auto scene = mo::COpenGLScene::Create();
  scene->getViewport()->setCustomBackgroundColor(mrpt::img::TColorf(
      o.background.r / 255.f, o.background.g / 255.f, o.background.b / 255.f));

  auto world = group("world");
  if (o.zUpDisplay) world->setPose(displayFromWorld());

  if (o.showGrid) world->insert(gridPlane(c, box, rayLength, o));
  if (o.showOriginAxes)
  {
    auto ax = mo::stock_objects::CornerXYZSimple(static_cast<float>(axes), 2.0f);
    ax->setName("origin");
    world->insert(ax);
  }

  auto traj = polyline(positions(c.trajectory), o.trajectoryColour, o.lineWidth);
  traj->setName("trajectory");
  world->insert(traj);
  if (c.groundTruth)
  {
    auto gt = polyline(positions(*c.groundTruth), o.groundTruthColour, o.lineWidth);
    gt->setName("gt_trajectory");
    world->insert(gt);
  }
  if (c.smoothed.size() >= 2)
  {
    auto sm = polyline(positions(c.smoothed), o.smoothedColour, o.lineWidth);
    sm->setName("smoothed_trajectory");
    world->insert(sm);
  }

  std::optional<core::TStampedPose> cur = c.currentCamera;
  if (!cur && !c.trajectory.empty()) cur = c.trajectory.back();
  if (cur && cur->p_W_C.allFinite() && cur->q_W_C.allFinite())
    world->insert(cameraObject(*cur, c.camera.get(), frustum, axes, o));

  addMap(*world, c, rayLength, o.underflowRange > 0 ? o.underflowRange : 100.0 * rayLength, o);
  addTracks(*world, c, o);

  if (!c.title.empty())
  {
    auto t = mo::CText::Create(c.title);
    t->setName("title");
    t->setColor_u8(toMrptColour(o.textColour));
    // Above the content: "up" is -y in W.
    const Vec3 p(box.min.x(), box.min.y() - 0.1 * extent, box.centre().z());
    t->setLocation(p[0], p[1], p[2]);
    world->insert(t);
  }
  scene->insert(world);
  return scene;
}

void saveSceneFile(const mo::COpenGLScene& scene, const std::string& path)
{
  bool ok = false;
  try
  {
    ok = scene.saveToFile(path);
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error("viz::saveSceneFile: cannot write " + path + ": " + e.what());
  }
  if (!ok || !std::filesystem::exists(path))
    throw std::runtime_error("viz::saveSceneFile: cannot write " + path);
}

mo::COpenGLScene::Ptr loadSceneFile(const std::string& path)
{
  if (!std::filesystem::is_regular_file(path))
    throw std::runtime_error("viz::loadSceneFile: no such file: " + path);
  auto scene = mo::COpenGLScene::Create();
  bool ok = false;
  try
  {
    ok = scene->loadFromFile(path);
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error("viz::loadSceneFile: cannot read " + path + ": " + e.what());
  }
  if (!ok) throw std::runtime_error("viz::loadSceneFile: not a 3Dscene file: " + path);
  return scene;
}

std::vector<mo::CRenderizable::Ptr> findObjectsByPrefix(
    const mo::COpenGLScene& scene, const std::string& prefix)
{
  std::vector<mo::CRenderizable::Ptr> out;
  const auto vp = scene.getViewport("main");
  if (!vp) return out;
  for (const auto& obj : *vp) collect(obj, prefix, out);
  return out;
}

mo::CRenderizable::Ptr findObject(const mo::COpenGLScene& scene, const std::string& name)
{
  for (const auto& obj : findObjectsByPrefix(scene, name))
    if (obj->getName() == name) return obj;
  return nullptr;
}
TSceneOptions sceneOptionsFitting(const TSceneContent& content)
{
  Eigen::AlignedBox3d box;
  for (const auto& p : content.trajectory) box.extend(p.p_W_C);
  for (const auto& p : content.points)
    if (p.depthKnown) box.extend(p.p_W);
  const double size = box.isEmpty() ? 1.0 : std::max(box.diagonal().norm(), 0.2);
  TSceneOptions so;
  so.showOriginAxes = false;
  so.frustumDepth = 0.08 * size;
  so.axesLength = 0.05 * size;
  so.rayLength = 0.5 * size;
  so.gridSpacing = 0.1 * size;
  return so;
}
}  // namespace immslam::viz
