/* imm-monoslam — dataset folder image source. */
#include <immslam/camera/CCameraModel.h>
#include <immslam/core/TTrajectory.h>
#include <immslam/io/CDatasetFolderSource.h>
#include <immslam/math/text.h>

#include "image_convert.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <istream>
#include <sstream>
#include <stdexcept>

namespace fs = std::filesystem;

namespace immslam::io
{
std::vector<TDatasetEntry> parseRgbTxt(std::istream& in, const std::string& fileLabel)
{
  std::vector<TDatasetEntry> out;
  std::string raw;
  std::size_t lineNo = 0;
  while (std::getline(in, raw))
  {
    ++lineNo;
    const std::string line = math::trim(raw);
    if (line.empty() || line[0] == '#') continue;
    TDatasetEntry e;
    e.line = lineNo;
    const std::string where = fileLabel + ":" + std::to_string(lineNo) + ": ";
    const auto sep = line.find_first_of(" \t");
    if (sep == std::string::npos)
    {
      e.error = where + "malformed line '" + line + "' (expected 'timestamp path')";
      out.push_back(std::move(e));
      continue;
    }
    const std::string stamp = line.substr(0, sep);
    e.path = math::trim(line.substr(sep));  // the rest of the line: paths may contain spaces
    errno = 0;
    char* end = nullptr;
    const double t = std::strtod(stamp.c_str(), &end);
    if (end != stamp.c_str() + stamp.size() || errno == ERANGE || !std::isfinite(t))
    {
      e.error = where + "malformed timestamp '" + stamp + "' in line '" + line + "'";
      out.push_back(std::move(e));
      continue;
    }
    e.timestamp = t;
    out.push_back(std::move(e));
  }
  return out;
}

CDatasetFolderSource::CDatasetFolderSource(const std::string& folder) : m_folder(folder)
{
  std::error_code ec;
  if (!fs::is_directory(folder, ec))
    throw std::runtime_error("dataset folder not found (or not a directory): " + folder);
  m_rgbTxt = (fs::path(folder) / "rgb.txt").string();
  std::ifstream in(m_rgbTxt);
  if (!in) throw std::runtime_error("cannot open " + m_rgbTxt + " (every dataset folder needs one)");
  m_entries = parseRgbTxt(in, m_rgbTxt);
  if (in.bad()) throw std::runtime_error("read error in " + m_rgbTxt);
  if (m_entries.empty())
    throw std::runtime_error(m_rgbTxt + ": no frame listed (the file is empty or holds only comments)");

  const std::string calib = (fs::path(folder) / "calib.txt").string();
  if (fs::exists(calib, ec)) m_calib = camera::loadCalibFile(calib);

  const std::string gt = (fs::path(folder) / "groundtruth.txt").string();
  if (fs::exists(gt, ec)) m_gt = core::readTumTrajectory(gt);
}

std::string CDatasetFolderSource::imagePath(const TDatasetEntry& e) const
{
  const fs::path p(e.path);
  return p.is_absolute() ? p.string() : (fs::path(m_folder) / p).string();
}

ENextStatus CDatasetFolderSource::next(TFrame& frame, std::string& why)
{
  why.clear();
  if (m_cursor >= m_entries.size()) return ENextStatus::End;
  const std::size_t idx = m_cursor++;
  const TDatasetEntry& e = m_entries[idx];
  if (!e.error.empty())
  {
    why = e.error;
    return ENextStatus::Skipped;
  }
  TFrame f;
  f.timestamp = e.timestamp;
  f.index = idx;
  f.origin = e.path;
  f.camera = m_calib;
  std::string sub;
  if (!detail::loadFrameImages(imagePath(e), f, sub))
  {
    why = sub + " (" + m_rgbTxt + ":" + std::to_string(e.line) + ")";
    return ENextStatus::Skipped;
  }
  frame = std::move(f);
  return ENextStatus::Frame;
}

std::string CDatasetFolderSource::describe() const
{
  std::ostringstream s;
  s << "dataset folder " << m_folder << " (" << m_entries.size() << " frames";
  if (m_calib) s << ", " << m_calib->modelName() << " camera";
  else s << ", no calib.txt";
  if (m_gt) s << ", ground truth " << m_gt->size() << " poses";
  s << ")";
  return s.str();
}
}  // namespace immslam::io
