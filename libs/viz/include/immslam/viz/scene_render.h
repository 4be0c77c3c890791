/* imm-monoslam — offscreen snapshots (PNG) of MRPT scenes through mrpt::opengl::CFBORender.
 *
 * CFBORender renders through EGL with no X display; on Debian 12 this needs at run time the
 * packages libegl1 + libegl-mesa0 (EGL), libgl1-mesa-dri (the software rasterizer swrast/llvmpipe)
 * and libopengl0 + libglu1-mesa (pulled in by libmrpt-opengl2.5). Without them the functions below
 * return false with the reason instead of throwing.
 */
#pragma once

#include <immslam/viz/scene.h>

#include <mrpt/opengl/COpenGLScene.h>
#include <opencv2/core.hpp>

#include <limits>
#include <string>

namespace immslam::viz
{
/** Where the snapshot is taken from. */
enum class EView
{
  ThreeQuarter,  ///< from behind, to the right of and above the content (perspective)
  Top            ///< looking down the display's z axis (W's y: "down" for the first camera)
};

/** Camera of a snapshot. The view always fits the box of the scene's finite content. */
struct TRenderOptions
{
  EView view = EView::ThreeQuarter;  ///< preset direction
  /** Azimuth/elevation of the eye around the box centre in the display frame (degrees; NaN: the
   * preset's, i.e. -135/30 for ThreeQuarter and 180/89.9 for Top, so that W's forward z points up
   * in the top view). */
  double azimuthDeg = std::numeric_limits<double>::quiet_NaN();
  double elevationDeg = std::numeric_limits<double>::quiet_NaN();  ///< see azimuthDeg
  double fovDeg = 40.0;  ///< vertical field of view of the snapshot camera (perspective views)
  bool orthographicTop = true;  ///< the top view is orthographic (a true map, no perspective)
  double margin = 1.08;  ///< >= 1: extra room around the fitted content
  /** If set, fit this box (in the scene's display frame) instead of the computed one. */
  std::optional<TBox3> box;
  /** Text drawn (with OpenCV, crisper than MRPT's bitmap CText) in the top-left corner; empty:
   * the string of the scene's "title" CText, if any. */
  std::string caption;
  /** Also draw the scene's 3-D "title" CText (it floats among the content; off by default). */
  bool showSceneTitle = false;
};

/** The box, in the display frame of the main viewport, of the scene's finite content: line
 * segments, point clouds, and the origins of every other object, composed through the poses of
 * their CSetOfObjects parents. The grid (CGridPlaneXZ/XY), text and objects named "origin" are
 * left out; rays ("map_rays") are included.
 * \param withEllipsoids also the surfaces of CEllipsoid3D / CEllipsoidInverseDepth3D (measured on
 *        a copy of the scene), except those larger than the rest of the content (the cones of
 *        unknown-depth features, which reach MRPT's underflow range). */
TBox3 sceneContentBox(const mrpt::opengl::COpenGLScene& scene, bool withEllipsoids = true);

/** True if an offscreen EGL context can be created here (tries once, ~0.1 s).
 * \param whyNot receives the reason when false. */
bool offscreenRenderingAvailable(std::string* whyNot = nullptr);

/** Renders the scene into a BGR image of width x height pixels.
 * \return false (with the reason in whyNot) if offscreen rendering is unavailable or failed;
 *         never throws for that.
 * \throws std::runtime_error if width/height are not positive. */
bool renderScene(const mrpt::opengl::COpenGLScene& scene, int width, int height,
    const TRenderOptions& options, cv::Mat& bgr, std::string* whyNot = nullptr);

/** renderScene() then writes a PNG.
 * \return false (with the reason) if rendering is unavailable.
 * \throws std::runtime_error naming the path if the PNG cannot be written. */
bool renderScenePng(const mrpt::opengl::COpenGLScene& scene, const std::string& png, int width,
    int height, const TRenderOptions& options = TRenderOptions(), std::string* whyNot = nullptr);
}  // namespace immslam::viz
