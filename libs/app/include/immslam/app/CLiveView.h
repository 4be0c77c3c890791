/* imm-monoslam — optional live windows (MRPT CDisplayWindow / CDisplayWindow3D): the overlay image
 * every frame and the 3-D scene every few frames. Only in the application, never in the estimator
 * libraries; opened only with a display (DISPLAY set) and without --no-gui. */
#pragma once

#include <immslam/viz/scene.h>

#include <opencv2/core/mat.hpp>

#include <memory>
#include <string>

namespace immslam::app
{
class CLiveView
{
 public:
  /** True if windows may be opened: not disabled and an X display is present (MRPT stalls ~8 s and
   * shows nothing when creating a window without one, MRPT_NOTES.md). */
  static bool available(bool noGui);

  CLiveView();
  ~CLiveView();
  CLiveView(const CLiveView&) = delete;
  CLiveView& operator=(const CLiveView&) = delete;

  /** Shows an overlay image (BGR). */
  void showImage(const cv::Mat& bgr);
  /** Replaces the content of the 3-D window. */
  void showScene(const viz::TSceneContent& content);
  /** False once the user closed a window (the run goes on without it). */
  bool isOpen() const;

 private:
  struct TImpl;
  std::unique_ptr<TImpl> m_impl;
};
}  // namespace immslam::app
