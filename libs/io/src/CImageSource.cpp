/* imm-monoslam — opening an image source by what a path is. */
#include <immslam/io/CDatasetFolderSource.h>
#include <immslam/io/CImageSource.h>
#include <immslam/io/CRawlogSource.h>
#include <immslam/io/CVideoFileSource.h>

#include <filesystem>
#include <stdexcept>

namespace immslam::io
{
CImageSource::Ptr openImageSource(const std::string& path, const std::string& rawlogSensorLabel)
{
  namespace fs = std::filesystem;
  std::error_code ec;
  const auto st = fs::status(path, ec);
  if (ec || !fs::exists(st))
    throw std::runtime_error("input not found: " + path + " (expected a dataset folder, a .rawlog file or a video file)");
  if (fs::is_directory(st)) return std::make_unique<CDatasetFolderSource>(path);
  if (isVideoFile(path)) return std::make_unique<CVideoFileSource>(path);
  // Any other existing file (normally *.rawlog) is read as a rawlog; CRawlogSource throws naming
  // the file if it is not one.
  return std::make_unique<CRawlogSource>(path, rawlogSensorLabel);
}
}  // namespace immslam::io
