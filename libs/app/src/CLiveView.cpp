/* imm-monoslam — live MRPT windows of the application. */
#include <immslam/app/CLiveView.h>

#include <mrpt/gui/CDisplayWindow.h>
#include <mrpt/gui/CDisplayWindow3D.h>
#include <mrpt/img/CImage.h>
#include <mrpt/opengl/COpenGLScene.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cstdlib>

namespace immslam::app
{
struct CLiveView::TImpl
{
  mrpt::gui::CDisplayWindow::Ptr image;
  mrpt::gui::CDisplayWindow3D::Ptr scene;
};

bool CLiveView::available(bool noGui)
{
  const char* d = std::getenv("DISPLAY");
  return !noGui && d && *d;
}

CLiveView::CLiveView() : m_impl(std::make_unique<TImpl>())
{
  m_impl->image = mrpt::gui::CDisplayWindow::Create("imm-monoslam: image", 640, 480);
  m_impl->image->setPos(10, 10);
  m_impl->scene = mrpt::gui::CDisplayWindow3D::Create("imm-monoslam: map", 800, 600);
  m_impl->scene->setPos(680, 10);
}

CLiveView::~CLiveView() = default;

void CLiveView::showImage(const cv::Mat& bgr)
{
  if (m_impl->image && m_impl->image->isOpen()) m_impl->image->showImage(mrpt::img::CImage(bgr, mrpt::img::DEEP_COPY));
}

void CLiveView::showScene(const viz::TSceneContent& content)
{
  if (!m_impl->scene || !m_impl->scene->isOpen()) return;
  const viz::TSceneOptions so = viz::sceneOptionsFitting(content);
  const auto built = viz::buildScene(content, so);
  {
    m_impl->scene->get3DSceneAndLock() = built;
    m_impl->scene->unlockAccess3DScene();
  }
  // Look at the trajectory and the map (MRPT's display frame is z up: our y down is its -z).
  Eigen::AlignedBox3d box;
  for (const auto& p : content.trajectory) box.extend(p.p_W_C);
  for (const auto& p : content.points)
    if (p.depthKnown) box.extend(p.p_W);
  if (!box.isEmpty())
  {
    const double size = std::max(box.diagonal().norm(), 0.2);
    const Vec3 c = box.center();
    m_impl->scene->setCameraPointingToPoint(static_cast<float>(c.z()), static_cast<float>(-c.x()),
                                            static_cast<float>(-c.y()));
    m_impl->scene->setCameraZoom(static_cast<float>(2.0 * size));
  }
  m_impl->scene->forceRepaint();
}

bool CLiveView::isOpen() const
{
  return (m_impl->image && m_impl->image->isOpen()) || (m_impl->scene && m_impl->scene->isOpen());
}
}  // namespace immslam::app
