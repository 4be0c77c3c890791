/* imm-monoslam — overlay PNG/video writer. */
#include <immslam/viz/COverlayWriter.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <cctype>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

namespace immslam::viz
{
struct COverlayWriter::TVideo
{
  cv::VideoWriter writer;
  cv::Size size;
};

namespace
{
/** The pattern with its single integer conversion made a long one ("%06d" -> "%06ld"), or "" if
 * the pattern does not hold exactly one integer conversion (other '%' only as "%%"). */
std::string longPattern(const std::string& p)
{
  int conversions = 0;
  std::string out;
  for (size_t i = 0; i < p.size(); ++i)
  {
    if (p[i] != '%')
    {
      out += p[i];
      continue;
    }
    if (i + 1 < p.size() && p[i + 1] == '%')
    {
      out += "%%";
      ++i;
      continue;
    }
    size_t j = i + 1;
    while (j < p.size() && std::isdigit(static_cast<unsigned char>(p[j]))) ++j;
    const std::string width = p.substr(i + 1, j - i - 1);
    if (j < p.size() && p[j] == 'l') ++j;
    if (j >= p.size() || p[j] != 'd') return "";
    out += "%" + width + "ld";
    ++conversions;
    i = j;
  }
  return conversions == 1 ? out : "";
}
}  // namespace

COverlayWriter::COverlayWriter(const TOptions& o) : m_opts(o)
{
  if (o.everyN < 1)
    throw std::runtime_error("COverlayWriter: everyN must be >= 1, got " + std::to_string(o.everyN));
  if (!(o.videoFps > 0)) throw std::runtime_error("COverlayWriter: videoFps must be > 0");
  m_longPattern = longPattern(o.pattern);
  if (m_longPattern.empty())
    throw std::runtime_error("COverlayWriter: pattern must hold one integer conversion: " + o.pattern);
  if (!o.folder.empty())
  {
    std::error_code ec;
    std::filesystem::create_directories(o.folder, ec);
    if (ec || !std::filesystem::is_directory(o.folder))
      throw std::runtime_error("COverlayWriter: cannot create folder " + o.folder);
  }
}

COverlayWriter::~COverlayWriter() { close(); }

void COverlayWriter::close()
{
  if (m_video) m_video->writer.release();
  m_video.reset();
}

std::string COverlayWriter::pngPath(long frameIndex) const
{
  char buf[512];
  std::snprintf(buf, sizeof buf, m_longPattern.c_str(), frameIndex);
  return (std::filesystem::path(m_opts.folder) / buf).string();
}

bool COverlayWriter::write(long frameIndex, const cv::Mat& bgr)
{
  if (frameIndex % m_opts.everyN != 0 || bgr.empty()) return false;
  if (m_opts.folder.empty() && m_opts.videoPath.empty()) return false;
  cv::Mat img = bgr;
  if (img.channels() == 1) cv::cvtColor(bgr, img, cv::COLOR_GRAY2BGR);
  if (!m_opts.folder.empty())
  {
    const std::string path = pngPath(frameIndex);
    bool ok = false;
    try
    {
      ok = cv::imwrite(path, img);
    }
    catch (const cv::Exception& e)
    {
      throw std::runtime_error("COverlayWriter: cannot write " + path + ": " + e.what());
    }
    if (!ok) throw std::runtime_error("COverlayWriter: cannot write " + path);
  }
  if (!m_opts.videoPath.empty())
  {
    if (!m_video)
    {
      auto v = std::make_unique<TVideo>();
      v->size = img.size();
      v->writer.open(m_opts.videoPath, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), m_opts.videoFps,
          v->size, true);
      if (!v->writer.isOpened())
        throw std::runtime_error("COverlayWriter: cannot open video " + m_opts.videoPath);
      m_video = std::move(v);
    }
    if (img.size() != m_video->size)
    {
      cv::Mat r;
      cv::resize(img, r, m_video->size, 0, 0, cv::INTER_AREA);
      m_video->writer.write(r);
    }
    else
      m_video->writer.write(img);
  }
  ++m_written;
  return true;
}
}  // namespace immslam::viz
