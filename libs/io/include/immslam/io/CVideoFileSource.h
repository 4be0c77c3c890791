/* imm-monoslam — image source reading a video file (any format OpenCV's FFmpeg back end decodes). */
#pragma once

#include <immslam/io/CImageSource.h>

#include <memory>
#include <string>

namespace cv
{
class VideoCapture;
}

namespace immslam::io
{
/** True if `path` names a video file by its extension (.mp4 .avi .mkv .mov .webm .mpg .mpeg .m4v
 * .wmv .flv .ogv .3gp, any case): openImageSource() then opens a CVideoFileSource. */
bool isVideoFile(const std::string& path);

/** Frames of a video file, decoded by cv::VideoCapture: TFrame::colour (BGR) and TFrame::grey,
 * TFrame::timestamp = index / frame rate (the container's, or the one given), no calibration (a video
 * carries none: give --calib). The end of the decodable stream ends the run (a truncated file ends
 * cleanly where its frames stop); an empty or grey-only decode is converted as needed. */
class CVideoFileSource : public CImageSource
{
 public:
  /** \param fps frame rate for the timestamps (0 = the container's; 30 if it has none).
   * \throws std::runtime_error naming the file if it does not exist or cannot be decoded. */
  explicit CVideoFileSource(const std::string& path, double fps = 0);
  ~CVideoFileSource() override;

  ENextStatus next(TFrame& frame, std::string& why) override;
  std::string describe() const override;
  /** The container's frame count (an estimate for some formats). */
  std::size_t sizeHint() const override { return m_count; }
  /** Frame rate used for the timestamps. */
  double fps() const { return m_fps; }

 private:
  std::string m_path;
  std::unique_ptr<cv::VideoCapture> m_cap;
  double m_fps = 30.0;
  std::size_t m_count = 0;
  std::size_t m_index = 0;
};
}  // namespace immslam::io
