/* imm-monoslam — dataset folder writer. */
#include <immslam/io/CDatasetWriter.h>

#include <opencv2/imgcodecs.hpp>

#include <cstdio>
#include <filesystem>
#include <stdexcept>

namespace fs = std::filesystem;

namespace immslam::io
{
CDatasetWriter::CDatasetWriter(const std::string& folder, const camera::CCameraModel& cam, const std::string& comment)
    : m_folder(folder), m_comment(comment)
{
  std::error_code ec;
  fs::create_directories(fs::path(folder) / "rgb", ec);
  if (ec) throw std::runtime_error("cannot create " + (fs::path(folder) / "rgb").string() + ": " + ec.message());
  camera::saveCalibFile(cam, (fs::path(folder) / "calib.txt").string());
  const std::string rgb = (fs::path(folder) / "rgb.txt").string();
  m_rgb.open(rgb, std::ios::trunc);
  if (!m_rgb) throw std::runtime_error("cannot write " + rgb);
  if (!m_comment.empty()) m_rgb << "# " << m_comment << "\n";
  m_rgb << "# timestamp filename\n";
}

CDatasetWriter::~CDatasetWriter()
{
  try
  {
    close();
  }
  catch (...)
  {
    // A destructor never throws; call close() to see errors.
  }
}

std::string CDatasetWriter::addFrame(double timestamp, const cv::Mat& image, const core::TStampedPose* gt)
{
  if (!m_rgb.is_open()) throw std::runtime_error("CDatasetWriter for " + m_folder + " is closed");
  char name[32];
  std::snprintf(name, sizeof(name), "rgb/%06zu.png", m_count);
  const std::string file = (fs::path(m_folder) / name).string();
  bool ok = false;
  try
  {
    ok = !image.empty() && cv::imwrite(file, image);
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error("cannot write image " + file + ": " + e.what());
  }
  if (!ok) throw std::runtime_error("cannot write image " + file + (image.empty() ? " (empty image)" : ""));
  char stamp[64];
  std::snprintf(stamp, sizeof(stamp), "%.6f", timestamp);
  m_rgb << stamp << ' ' << name << '\n';
  if (!m_rgb) throw std::runtime_error("write error in " + (fs::path(m_folder) / "rgb.txt").string());
  if (gt)
  {
    const std::string gtFile = (fs::path(m_folder) / "groundtruth.txt").string();
    if (!m_gtOpen)
    {
      m_gt.open(gtFile, std::ios::trunc);
      if (!m_gt) throw std::runtime_error("cannot write " + gtFile);
      m_gtOpen = true;
      if (!m_comment.empty()) m_gt << "# " << m_comment << "\n";
      m_gt << "# timestamp tx ty tz qx qy qz qw  (T_world_camera, camera x right, y down, z forward)\n";
    }
    core::TStampedPose p = *gt;
    p.timestamp = timestamp;
    m_gt << core::formatTumLine(p) << '\n';
    if (!m_gt) throw std::runtime_error("write error in " + gtFile);
  }
  ++m_count;
  return name;
}

void CDatasetWriter::close()
{
  if (m_rgb.is_open())
  {
    m_rgb.close();
    if (m_rgb.fail()) throw std::runtime_error("write error closing " + (fs::path(m_folder) / "rgb.txt").string());
  }
  if (m_gt.is_open())
  {
    m_gt.close();
    if (m_gt.fail())
      throw std::runtime_error("write error closing " + (fs::path(m_folder) / "groundtruth.txt").string());
  }
}
}  // namespace immslam::io
