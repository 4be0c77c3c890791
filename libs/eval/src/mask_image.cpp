/* imm-monoslam — reading object masks with OpenCV (a private dependency of libs/eval). */
#include <immslam/eval/classification_truth.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <stdexcept>

namespace immslam::eval
{
TMaskImage readMaskImage(const std::string& path)
{
  cv::Mat m;
  try
  {
    m = cv::imread(path, cv::IMREAD_UNCHANGED);
  }
  catch (const cv::Exception& e)
  {
    throw std::runtime_error(path + ": cannot read mask image (" + e.what() + ")");
  }
  if (m.empty()) throw std::runtime_error(path + ": cannot read mask image");
  // Any non-zero colour channel of any depth marks a moving object (an alpha channel is ignored).
  if (m.channels() > 1)
  {
    std::vector<cv::Mat> ch;
    cv::split(m, ch);
    const std::size_t nColour = ch.size() == 4 ? 3 : ch.size();
    cv::Mat any = ch[0] != 0;
    for (std::size_t i = 1; i < nColour; ++i) any |= ch[i] != 0;
    m = any;
  }
  else if (m.depth() != CV_8U)
    m = m != 0;
  return TMaskImage::fromBuffer(m.ptr<std::uint8_t>(0), m.cols, m.rows, m.step);
}
}  // namespace immslam::eval
