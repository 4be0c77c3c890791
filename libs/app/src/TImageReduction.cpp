/* imm-monoslam — [input] max_image_width (see TImageReduction.h). */
#include "TImageReduction.h"

#include <opencv2/imgproc.hpp>

#include <sstream>

namespace immslam::app::detail
{
TImageReduction::TImageReduction(cv::Size first, int maxWidth) : factor(1), full(first)
{
  while (maxWidth > 0 && full.width / factor > maxWidth) factor *= 2;
  kept = cv::Rect(0, 0, full.width - full.width % factor, full.height - full.height % factor);
}

std::string TImageReduction::describe(int maxWidth) const
{
  std::ostringstream s;
  s << "images are " << full.width << "x" << full.height << ": processed at " << kept.width / factor << "x"
    << kept.height / factor << " ([input] max_image_width = " << maxWidth << ")";
  if (kept.size() != full) s << ", after dropping their last columns/rows to " << kept.width << "x" << kept.height;
  return s.str();
}

camera::CCameraModel::Ptr TImageReduction::camera(const camera::CCameraModel& c) const
{
  return camera::makeCameraModel(c.modelName(), kept.width, kept.height, c.parameters())->scaled(1.0 / factor);
}

void TImageReduction::apply(io::TFrame& f) const
{
  if (factor <= 1 || f.grey.size() != full) return;
  const cv::Size small(kept.width / factor, kept.height / factor);
  cv::resize(f.grey(kept), f.grey, small, 0, 0, cv::INTER_AREA);
  if (!f.colour.empty()) cv::resize(f.colour(kept), f.colour, small, 0, 0, cv::INTER_AREA);
}

cv::Mat TImageReduction::applyToMask(const cv::Mat& m) const
{
  if (factor <= 1 || m.size() != full) return m;
  cv::Mat small;
  cv::resize(m(kept), small, cv::Size(kept.width / factor, kept.height / factor), 0, 0, cv::INTER_AREA);
  return small != 0;
}
}  // namespace immslam::app::detail
