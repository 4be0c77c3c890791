/* imm-monoslam — video file image source (see CVideoFileSource.h). */
#include <immslam/io/CVideoFileSource.h>

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <sstream>
#include <stdexcept>

namespace immslam::io
{
bool isVideoFile(const std::string& path)
{
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  for (const char* v : {".mp4", ".avi", ".mkv", ".mov", ".webm", ".mpg", ".mpeg", ".m4v", ".wmv", ".flv", ".ogv", ".3gp"})
    if (ext == v) return true;
  return false;
}

CVideoFileSource::CVideoFileSource(const std::string& path, double fps) : m_path(path)
{
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw std::runtime_error("video file not found: " + path);
  m_cap = std::make_unique<cv::VideoCapture>(path, cv::CAP_FFMPEG);
  if (!m_cap->isOpened()) m_cap = std::make_unique<cv::VideoCapture>(path);  // any other back end
  if (!m_cap->isOpened()) throw std::runtime_error("cannot decode video file " + path);
  const double containerFps = m_cap->get(cv::CAP_PROP_FPS);
  m_fps = fps > 0 ? fps : (containerFps > 0 && containerFps < 1000 ? containerFps : 30.0);
  const double n = m_cap->get(cv::CAP_PROP_FRAME_COUNT);
  m_count = n > 0 && n < 1e9 ? static_cast<std::size_t>(n) : 0;
}

CVideoFileSource::~CVideoFileSource() = default;

ENextStatus CVideoFileSource::next(TFrame& frame, std::string& why)
{
  cv::Mat img;
  if (!m_cap->read(img) || img.empty())
  {
    why.clear();
    // The header's frame count is exact for most containers and an estimate (duration x rate) for a
    // few: an end well before it is a cut or damaged file, said in the summary (not an error).
    if (m_count > 0 && m_index + std::max<std::size_t>(2, m_count / 50) < m_count)
      why = "video file " + m_path + " ended after " + std::to_string(m_index) + " of the " + std::to_string(m_count) +
            " frames its header announces (cut or damaged?)";
    return ENextStatus::End;
  }
  frame = TFrame();
  frame.index = m_index;
  frame.timestamp = static_cast<double>(m_index) / m_fps;
  frame.origin = "frame " + std::to_string(m_index) + " of " + m_path;
  ++m_index;
  if (img.channels() == 3)
  {
    frame.colour = img;
    cv::cvtColor(img, frame.grey, cv::COLOR_BGR2GRAY);
  }
  else if (img.channels() == 4)
  {
    cv::cvtColor(img, frame.colour, cv::COLOR_BGRA2BGR);
    cv::cvtColor(img, frame.grey, cv::COLOR_BGRA2GRAY);
  }
  else
    frame.grey = img;
  if (frame.grey.depth() != CV_8U) frame.grey.convertTo(frame.grey, CV_8U);
  return ENextStatus::Frame;
}

std::string CVideoFileSource::describe() const
{
  std::ostringstream s;
  s << "video file " << m_path << " (" << m_count << " frames, " << m_fps << " Hz)";
  return s.str();
}
}  // namespace immslam::io
