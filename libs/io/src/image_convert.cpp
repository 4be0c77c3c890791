/* imm-monoslam — image conversions shared by the image sources and dataset2rawlog. */
#include "image_convert.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <system_error>

namespace immslam::io::detail
{
bool setFrameImages(const cv::Mat& raw, TFrame& frame, std::string& why)
{
  frame.grey.release();
  frame.colour.release();
  if (raw.empty())
  {
    why = "empty image";
    return false;
  }
  cv::Mat img8;
  switch (raw.depth())
  {
    case CV_8U: img8 = raw; break;
    case CV_16U: raw.convertTo(img8, CV_8U, 1.0 / 256.0); break;
    default:
      why = "unsupported pixel depth (OpenCV depth code " + std::to_string(raw.depth()) +
            "; 8 or 16 bits expected)";
      return false;
  }
  switch (img8.channels())
  {
    case 1: frame.grey = img8; break;
    case 2:
      cv::extractChannel(img8, frame.grey, 0);  // grey + alpha
      break;
    case 3:
      frame.colour = img8;
      cv::cvtColor(img8, frame.grey, cv::COLOR_BGR2GRAY);
      break;
    case 4:
      cv::cvtColor(img8, frame.colour, cv::COLOR_BGRA2BGR);
      cv::cvtColor(img8, frame.grey, cv::COLOR_BGRA2GRAY);
      break;
    default:
      why = "unsupported number of channels (" + std::to_string(img8.channels()) + ")";
      return false;
  }
  return true;
}

bool loadFrameImages(const std::string& path, TFrame& frame, std::string& why)
{
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
  {
    why = "missing image file " + path;
    return false;
  }
  cv::Mat raw;
  try
  {
    raw = cv::imread(path, cv::IMREAD_UNCHANGED);
  }
  catch (const std::exception& e)
  {
    why = "cannot decode image " + path + ": " + oneLine(e.what());
    return false;
  }
  if (raw.empty())
  {
    why = "cannot decode image " + path + " (corrupt or unsupported format)";
    return false;
  }
  std::string sub;
  if (!setFrameImages(raw, frame, sub))
  {
    why = "image " + path + ": " + sub;
    return false;
  }
  return true;
}

std::string mrptMessage(const std::string& text)
{
  const std::string flat = oneLine(text);
  static const std::string tag = "Message: ";
  std::string out;
  std::size_t pos = flat.find(tag);
  if (pos == std::string::npos) return flat;
  while (pos != std::string::npos)
  {
    const std::size_t b = pos + tag.size();
    std::size_t e = flat.size();
    for (const char* stop : {" Location: ", " Original exception", " Call stack", " ==== MRPT exception"})
      e = std::min(e, flat.find(stop, b) == std::string::npos ? flat.size() : flat.find(stop, b));
    std::string msg = flat.substr(b, e - b);
    while (!msg.empty() && (msg.back() == ' ' || msg.back() == ':')) msg.pop_back();
    if (!msg.empty()) out += (out.empty() ? "" : ": ") + msg;
    pos = flat.find(tag, e);
  }
  return out.empty() ? flat : out;
}

std::string oneLine(const std::string& text)
{
  std::string out;
  bool space = false;
  for (const char c : text)
  {
    if (std::isspace(static_cast<unsigned char>(c)))
      space = true;
    else
    {
      if (space && !out.empty()) out += ' ';
      space = false;
      out += c;
    }
  }
  return out;
}
}  // namespace immslam::io::detail
