/* imm-monoslam — offscreen PNG snapshots of MRPT scenes (CFBORender, EGL, no X needed). */
#include <immslam/viz/scene_render.h>

#include "cv_text.h"

#include <Eigen/Dense>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/opengl/CFBORender.h>
#include <mrpt/opengl/CGeneralizedEllipsoidTemplate.h>
#include <mrpt/opengl/CGridPlaneXY.h>
#include <mrpt/opengl/CGridPlaneXZ.h>
#include <mrpt/opengl/CPointCloudColoured.h>
#include <mrpt/opengl/CSetOfLines.h>
#include <mrpt/opengl/CSetOfObjects.h>
#include <mrpt/opengl/CText.h>
#include <mrpt/serialization/CArchive.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>

namespace immslam::viz
{
namespace mo = mrpt::opengl;

namespace
{
Vec3 toVec(const mrpt::math::TPoint3D& p) { return Vec3(p.x, p.y, p.z); }

/** Boxes of ellipsoid surfaces: one per ellipsoid, in the display frame. */
using TEllipsoidBoxes = std::vector<TBox3>;

void addObject(const mo::CRenderizable::Ptr& obj, const mrpt::poses::CPose3D& parent, TBox3& box,
    TEllipsoidBoxes* ellipsoids)
{
  if (!obj || !obj->isVisible()) return;
  const std::string& name = obj->getName();
  if (name == "origin" || name == "title") return;
  if (std::dynamic_pointer_cast<mo::CGridPlaneXZ>(obj) ||
      std::dynamic_pointer_cast<mo::CGridPlaneXY>(obj) || std::dynamic_pointer_cast<mo::CText>(obj))
    return;
  const mrpt::poses::CPose3D pose = parent + obj->getPoseRef();
  if (auto g = std::dynamic_pointer_cast<mo::CSetOfObjects>(obj))
  {
    for (const auto& child : *g) addObject(child, pose, box, ellipsoids);
    return;
  }
  if (auto lines = std::dynamic_pointer_cast<mo::CSetOfLines>(obj))
  {
    for (const auto& s : *lines)
    {
      box.add(toVec(pose.composePoint(s.point1)));
      box.add(toVec(pose.composePoint(s.point2)));
    }
    return;
  }
  if (auto pc = std::dynamic_pointer_cast<mo::CPointCloudColoured>(obj))
  {
    for (size_t i = 0; i < pc->size(); ++i)
    {
      const auto& p = pc->getPoint3Df(i);
      box.add(toVec(pose.composePoint(mrpt::math::TPoint3D(p.x, p.y, p.z))));
    }
    return;
  }
  box.add(Vec3(pose.x(), pose.y(), pose.z()));
  auto e = std::dynamic_pointer_cast<mo::CGeneralizedEllipsoidTemplate<3>>(obj);
  if (e && ellipsoids)
  {
    // Generates the surface (CPU only) to know its extent; only done on throw-away copies.
    e->renderUpdateBuffers();
    const auto bb = e->getBoundingBoxLocal();
    TBox3 eb;
    for (int i = 0; i < 8; ++i)
      eb.add(toVec(pose.composePoint(mrpt::math::TPoint3D((i & 1) ? bb.max.x : bb.min.x,
          (i & 2) ? bb.max.y : bb.min.y, (i & 4) ? bb.max.z : bb.min.z))));
    ellipsoids->push_back(eb);
  }
}

/** Distance from the box centre to the eye so that the box fits the view (perspective), or, with
 * `ortho`, MRPT's orthographic zoom distance (measured on 2.5.8: the smaller image side spans half
 * the zoom distance). */
double fitDistance(const TBox3& box, double azDeg, double elDeg, double vfovDeg, double aspect,
    double margin, bool ortho)
{
  const double az = azDeg * M_PI / 180.0, el = elDeg * M_PI / 180.0;
  const Vec3 toEye(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  const Vec3 fwd = -toEye;
  Vec3 right = fwd.cross(Vec3::UnitZ());
  if (right.norm() < 1e-9) right = Vec3(std::sin(az), -std::cos(az), 0);
  right.normalize();
  const Vec3 up = right.cross(fwd);
  const double tv = std::tan(0.5 * vfovDeg * M_PI / 180.0), th = tv * aspect;
  const Vec3 c = box.centre();
  double d = 0, halfW = 0, halfH = 0, deep = 0;
  for (int i = 0; i < 8; ++i)
  {
    const Vec3 corner((i & 1) ? box.max.x() : box.min.x(), (i & 2) ? box.max.y() : box.min.y(),
        (i & 4) ? box.max.z() : box.min.z());
    const Vec3 v = (corner - c) * margin;
    const double towardEye = v.dot(toEye);
    d = std::max(d, towardEye + std::max(std::abs(v.dot(right)) / th, std::abs(v.dot(up)) / tv));
    halfW = std::max(halfW, std::abs(v.dot(right)));
    halfH = std::max(halfH, std::abs(v.dot(up)));
    deep = std::max(deep, towardEye);
  }
  if (ortho)
  {
    // Smaller side spans D/2: D = 4 * max(half extent along the smaller side, the other scaled).
    const double D = aspect >= 1 ? 4 * std::max(halfH, halfW / aspect)
                                 : 4 * std::max(halfW, halfH * aspect);
    return std::max({D, 2 * deep, 1e-3});  // the eye stays above the content
  }
  return std::max(d, 1e-3);
}

/** The useful line of an MRPT exception text (its "Message:" line), else the first line. */
std::string reasonOf(const std::string& what)
{
  const auto m = what.find("Message:");
  std::string s = m == std::string::npos ? what : what.substr(m + 8);
  const auto nl = s.find('\n');
  if (nl != std::string::npos) s.resize(nl);
  const auto b = s.find_first_not_of(" \t");
  return b == std::string::npos ? std::string("unknown error") : s.substr(b);
}

/** A fresh copy of the scene, through MRPT serialization. Objects cache OpenGL buffers of the
 * context that first drew them, and drawing them again from another CFBORender (another EGL
 * context) fails in MRPT 2.5.8 ("invalid value"); copies have no such cache. */
mo::COpenGLScene::Ptr freshCopy(const mo::COpenGLScene& scene)
{
  mrpt::io::CMemoryStream buf;
  auto arch = mrpt::serialization::archiveFrom(buf);
  arch << scene;
  buf.Seek(0);
  auto copy = mo::COpenGLScene::Create();
  arch >> *copy;
  return copy;
}
}  // namespace

TBox3 sceneContentBox(const mo::COpenGLScene& scene, bool withEllipsoids)
{
  TBox3 box;
  const auto vp = scene.getViewport("main");
  if (!vp) return box;
  for (const auto& obj : *vp) addObject(obj, mrpt::poses::CPose3D(), box, nullptr);
  if (!withEllipsoids) return box;
  // Ellipsoid surfaces, measured on a copy. Those larger than everything else together are the
  // unknown-depth cones reaching MRPT's underflow range: left out.
  TEllipsoidBoxes boxes;
  TBox3 ignored;
  const auto copy = freshCopy(scene);
  for (const auto& obj : *copy->getViewport("main"))
    addObject(obj, mrpt::poses::CPose3D(), ignored, &boxes);
  const double limit = std::max(box.diagonal(), 1e-6);
  for (const auto& eb : boxes)
    if (!eb.empty() && eb.diagonal() <= limit)
    {
      box.add(eb.min);
      box.add(eb.max);
    }
  return box;
}

bool offscreenRenderingAvailable(std::string* whyNot)
{
  try
  {
    mo::CFBORender probe(16, 16);
    return true;
  }
  catch (const std::exception& e)
  {
    if (whyNot)
      *whyNot = "offscreen EGL rendering unavailable (" + reasonOf(e.what()) +
                "); needs libegl1, libegl-mesa0, libgl1-mesa-dri";
    return false;
  }
}

namespace
{
/** The camera of renderScene(): looking at the scene's content box (or o.box) from the view's
 * azimuth and elevation, at the distance that fits it in a width x height image. */
mo::CCamera viewCamera(const mo::COpenGLScene& scene, int width, int height, const TRenderOptions& o)
{
  TBox3 box = o.box ? *o.box : sceneContentBox(scene);
  if (box.empty()) box.add(Vec3::Zero());
  // A flat box (e.g. a planar trajectory seen from above) still needs some depth to fit.
  const double ext = std::max(box.diagonal(), 1e-2);
  box.add(box.centre() - Vec3::Constant(0.02 * ext));
  box.add(box.centre() + Vec3::Constant(0.02 * ext));

  const bool top = o.view == EView::Top;
  const double az = std::isfinite(o.azimuthDeg) ? o.azimuthDeg : (top ? 180.0 : -135.0);
  const double el = std::isfinite(o.elevationDeg) ? o.elevationDeg : (top ? 89.9 : 30.0);
  const double fov = std::clamp(o.fovDeg, 5.0, 120.0);
  const bool ortho = top && o.orthographicTop;
  const double dist =
      fitDistance(box, az, el, fov, double(width) / height, std::max(1.0, o.margin), ortho);

  mo::CCamera cam;
  const Vec3 c = box.centre();
  cam.setPointingAt(
      static_cast<float>(c.x()), static_cast<float>(c.y()), static_cast<float>(c.z()));
  cam.setZoomDistance(static_cast<float>(dist));
  cam.setAzimuthDegrees(static_cast<float>(az));
  cam.setElevationDegrees(static_cast<float>(el));
  if (ortho)
    cam.setOrthogonal(true);
  else
  {
    cam.setProjectiveModel(true);
    cam.setProjectiveFOVdeg(static_cast<float>(fov));
  }

  return cam;
}
}  // namespace

bool renderScene(const mo::COpenGLScene& scene, int width, int height, const TRenderOptions& o,
    cv::Mat& bgr, std::string* whyNot)
{
  if (width <= 0 || height <= 0)
    throw std::runtime_error("viz::renderScene: image size must be positive, got " +
                             std::to_string(width) + "x" + std::to_string(height));
  const mo::CCamera cam = viewCamera(scene, width, height, o);

  std::unique_ptr<mo::CFBORender> render;
  try
  {
    render = std::make_unique<mo::CFBORender>(
        static_cast<unsigned>(width), static_cast<unsigned>(height));
  }
  catch (const std::exception& e)
  {
    if (whyNot)
      *whyNot = "offscreen EGL rendering unavailable (" + reasonOf(e.what()) +
                "); needs libegl1, libegl-mesa0, libgl1-mesa-dri";
    return false;
  }
  mrpt::img::CImage img;
  std::string caption = o.caption;
  try
  {
    const auto copy = freshCopy(scene);
    if (auto t = std::dynamic_pointer_cast<mo::CText>(findObject(*copy, "title")))
    {
      if (caption.empty()) caption = t->getString();
      t->setVisibility(o.showSceneTitle);
    }
    render->setCamera(*copy, cam);
    render->render_RGB(*copy, img);
  }
  catch (const std::exception& e)
  {
    if (whyNot) *whyNot = "offscreen rendering failed (" + reasonOf(e.what()) + ")";
    return false;
  }
  if (img.isEmpty())
  {
    if (whyNot) *whyNot = "offscreen rendering returned an empty image";
    return false;
  }
  const cv::Mat& m = img.asCvMatRef();
  if (m.channels() == 3)
    bgr = m.clone();
  else if (m.channels() == 4)
    cv::cvtColor(m, bgr, cv::COLOR_BGRA2BGR);
  else
    cv::cvtColor(m, bgr, cv::COLOR_GRAY2BGR);
  if (!caption.empty())
    drawTextBox(bgr, {caption}, cv::Point(8, 8), 0.55, cv::Scalar(0, 0, 0),
        cv::Scalar(255, 255, 255), 0.75);
  return true;
}

bool renderScenePng(const mo::COpenGLScene& scene, const std::string& png, int width, int height,
    const TRenderOptions& o, std::string* whyNot)
{
  cv::Mat bgr;
  if (!renderScene(scene, width, height, o, bgr, whyNot)) return false;
  bool ok = false;
  try
  {
    ok = cv::imwrite(png, bgr);
  }
  catch (const cv::Exception& e)
  {
    throw std::runtime_error("viz::renderScenePng: cannot write " + png + ": " + e.what());
  }
  if (!ok) throw std::runtime_error("viz::renderScenePng: cannot write " + png);
  return true;
}
}  // namespace immslam::viz
