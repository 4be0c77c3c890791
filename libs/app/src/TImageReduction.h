/* imm-monoslam — private to libs/app: [input] max_image_width, the power-of-two reduction of the
 * input images and of their calibration. */
#pragma once

#include <immslam/camera/CCameraModel.h>
#include <immslam/io/CImageSource.h>

#include <opencv2/core.hpp>

#include <string>

namespace immslam::app::detail
{
/** [input] max_image_width: the power-of-two reduction that brings the first frame's width to the
 * limit. A side the factor does not divide loses its last (at most factor - 1) columns or rows first,
 * which leaves the intrinsics as they are, so the scaled calibration is exact. Frames of another size
 * than the first are left alone (the size check skips them). */
struct TImageReduction
{
  int factor = 0;  ///< 0: not decided yet; 1: none
  cv::Size full;   ///< the first frame's size
  cv::Rect kept;   ///< the part of a full-size frame that is reduced

  /** Not decided yet. */
  TImageReduction() = default;
  /** The reduction of frames of size `first` to at most `maxWidth` columns (0: none). */
  TImageReduction(cv::Size first, int maxWidth);
  /** True once the first frame has decided it. */
  bool decided() const { return factor > 0; }
  /** "images are WxH: processed at wxh ([input] max_image_width = N)...", for the log. */
  std::string describe(int maxWidth) const;
  /** The calibration of a full-size frame for the reduced one. */
  camera::CCameraModel::Ptr camera(const camera::CCameraModel& c) const;
  /** Reduces a full-size frame's images in place (area averaging); other sizes are left alone. */
  void apply(io::TFrame& f) const;
  /** A full-size exclusion mask for the reduced frame: a reduced pixel is excluded if any of the
   * full-size pixels it averages is. */
  cv::Mat applyToMask(const cv::Mat& m) const;
};
}  // namespace immslam::app::detail
