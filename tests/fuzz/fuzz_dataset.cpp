/* Fuzz target: the dataset-folder parsers (rgb.txt: io::parseRgbTxt and io::CDatasetFolderSource;
 * groundtruth.txt: core::readTumTrajectory; calib.txt through the folder source). */
#include "fuzz_common.h"

#include <immslam/core/TTrajectory.h>
#include <immslam/io/CDatasetFolderSource.h>

#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <filesystem>
#include <sstream>

namespace immslam::fuzz
{
namespace
{
/** The test folder: rgb/a.png (8x6 grey) is created once; the text files are rewritten per input. */
const std::string& folder()
{
  static const std::string dir = [] {
    const std::string d = fuzzTempDir() + "/dataset";
    std::filesystem::create_directories(d + "/rgb");
    cv::Mat img(6, 8, CV_8UC1);
    for (int i = 0; i < img.rows * img.cols; ++i) img.data[i] = static_cast<uchar>(i * 5);
    cv::imwrite(d + "/rgb/a.png", img);
    return d;
  }();
  return dir;
}

/** The parts of the input separated by lines "%%". */
std::vector<std::string> splitParts(const std::string& text)
{
  std::vector<std::string> parts(1);
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line))
  {
    if (line == "%%" && parts.size() < 3)
      parts.emplace_back();
    else
      parts.back() += line + "\n";
  }
  return parts;
}
}  // namespace

int fuzzDataset(const std::uint8_t* data, std::size_t size)
{
  const auto parts = splitParts(std::string(reinterpret_cast<const char*>(data), size));
  const std::string& dir = folder();

  // rgb.txt, parsed from memory: malformed lines become entries with a reason naming the line.
  {
    std::istringstream in(parts[0]);
    for (const auto& e : io::parseRgbTxt(in, "fuzz/rgb.txt"))
    {
      if (!e.error.empty())
      {
        if (e.error.find("fuzz/rgb.txt:" + std::to_string(e.line)) == std::string::npos)
          fail("parseRgbTxt: the reason does not name the line: " + e.error);
      }
      else if (!std::isfinite(e.timestamp) || e.path.empty())
        fail("parseRgbTxt: an entry without error has timestamp " + std::to_string(e.timestamp) + " and path '" +
             e.path + "'");
    }
  }
  writeFile(dir + "/rgb.txt", parts[0]);
  std::error_code ec;
  std::filesystem::remove(dir + "/groundtruth.txt", ec);
  std::filesystem::remove(dir + "/calib.txt", ec);
  if (parts.size() > 1)
  {
    const std::string gt = dir + "/groundtruth.txt";
    writeFile(gt, parts[1]);
    try
    {
      for (const auto& p : core::readTumTrajectory(gt))
        if (!std::isfinite(p.timestamp) || !p.p_W_C.allFinite() || !p.q_W_C.allFinite() ||
            std::abs(p.q_W_C.norm() - 1) > 1e-9)
          fail("readTumTrajectory: a pose that is not finite or not unit");
    }
    catch (const std::exception& e)
    {
      requireMentions(e, gt, "readTumTrajectory");
    }
  }
  if (parts.size() > 2) writeFile(dir + "/calib.txt", parts[2]);

  // The folder source: opening may fail (naming the folder's file); reading never throws.
  std::unique_ptr<io::CDatasetFolderSource> src;
  try
  {
    src = std::make_unique<io::CDatasetFolderSource>(dir);
  }
  catch (const std::exception& e)
  {
    requireMentions(e, dir, "CDatasetFolderSource");
    return 0;
  }
  (void)src->describe();
  io::TFrame f;
  std::string why;
  for (int i = 0; i < 2000; ++i)
  {
    const auto st = src->next(f, why);
    if (st == io::ENextStatus::End) break;
    if (st == io::ENextStatus::Frame && (f.grey.empty() || f.grey.type() != CV_8UC1))
      fail("CDatasetFolderSource: a frame without an 8-bit grey image");
    if (st == io::ENextStatus::Skipped && why.empty()) fail("CDatasetFolderSource: skipped without a reason");
  }
  return 0;
}
}  // namespace immslam::fuzz
