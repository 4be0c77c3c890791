/* imm-monoslam — rawlog recorder (plain-observation layout, lossless embedded or PNG images). */
#include <immslam/camera/mrpt_camera.h>
#include <immslam/io/CRawlogRecorder.h>

#include "image_convert.h"

#include <mrpt/core/Clock.h>
#include <mrpt/img/CImage.h>
#include <mrpt/img/TCamera.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/obs/CObservationImage.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/serialization/CSerializable.h>
#include <mrpt/system/filesystem.h>

#include <opencv2/imgcodecs.hpp>

#include <cstdio>
#include <filesystem>
#include <optional>
#include <stdexcept>

namespace fs = std::filesystem;

namespace immslam::io
{
namespace
{
/** Sets MRPT's process-wide CImage::DISABLE_JPEG_COMPRESSION for its lifetime (colour images are
 * then serialized as raw BGR), then restores the previous value. */
class CNoJpegGuard
{
 public:
  CNoJpegGuard() : m_old(mrpt::img::CImage::DISABLE_JPEG_COMPRESSION())
  {
    mrpt::img::CImage::DISABLE_JPEG_COMPRESSION(true);
  }
  ~CNoJpegGuard() { mrpt::img::CImage::DISABLE_JPEG_COMPRESSION(m_old); }
  CNoJpegGuard(const CNoJpegGuard&) = delete;
  CNoJpegGuard& operator=(const CNoJpegGuard&) = delete;

 private:
  bool m_old;
};
}  // namespace

struct CRawlogRecorder::Impl
{
  std::string path;
  TRecorderOptions opts;
  mrpt::io::CFileGZOutputStream file;
  std::optional<mrpt::serialization::CArchive::UniquePtr> arch;
  bool open = false;
  std::size_t frames = 0;
  std::size_t objects = 0;
  std::string imagesDir;     ///< where external images go
  std::string imagesPrefix;  ///< prefix of the stored external name ("" for the MRPT default folder)

  // Cache of the last converted camera model.
  const camera::CCameraModel* lastCam = nullptr;
  mrpt::img::TCamera lastTCam;

  void requireOpen(const char* what) const
  {
    if (!open) throw std::runtime_error("rawlog recorder " + path + ": " + what + " after close()");
  }

  void writeObject(const mrpt::serialization::CSerializable& obj)
  {
    try
    {
      const CNoJpegGuard lossless;
      (**arch) << obj;
    }
    catch (const std::exception& e)
    {
      throw std::runtime_error("error writing rawlog " + path + ": " + detail::mrptMessage(e.what()));
    }
  }
};

CRawlogRecorder::CRawlogRecorder(const std::string& path, TRecorderOptions options)
    : m_impl(std::make_unique<Impl>())
{
  Impl& m = *m_impl;
  m.path = path;
  m.opts = std::move(options);
  if (m.opts.compressionLevel < 0 || m.opts.compressionLevel > 9)
    throw std::runtime_error("rawlog recorder " + path + ": compressionLevel " +
                             std::to_string(m.opts.compressionLevel) + " not in 0..9");
  const fs::path p(path);
  const fs::path dir = p.has_parent_path() ? p.parent_path() : fs::path(".");
  if (!m.opts.embedImages)
  {
    std::error_code ec;
    if (m.opts.imagesDir.empty())
    {
      // MRPT's convention: names relative to <dir>/<stem>_Images.
      m.imagesDir = (dir / (p.stem().string() + "_Images")).string();
      m.imagesPrefix.clear();
    }
    else
    {
      // Stored relative to the rawlog's folder when possible (CRawlogSource resolves both).
      m.imagesDir = m.opts.imagesDir;
      const fs::path rel = fs::absolute(m.imagesDir, ec).lexically_relative(fs::absolute(dir, ec));
      m.imagesPrefix = rel.empty() ? fs::absolute(m.imagesDir, ec).string() : rel.generic_string();
      m.imagesPrefix += "/";
    }
    fs::create_directories(m.imagesDir, ec);
    if (!fs::is_directory(m.imagesDir, ec))
      throw std::runtime_error("rawlog recorder: cannot create the images folder " + m.imagesDir);
  }
  std::string err;
  if (!m.file.open(path, m.opts.compressionLevel, err))
    throw std::runtime_error("cannot write rawlog " + path + (err.empty() ? "" : ": " + err));
  m.arch = mrpt::serialization::archiveUniquePtrFrom(m.file);
  m.open = true;
}

CRawlogRecorder::~CRawlogRecorder()
{
  try
  {
    close();
  }
  catch (...)
  {
  }
}

void CRawlogRecorder::record(const TFrame& frame)
{
  Impl& m = *m_impl;
  m.requireOpen("record()");
  const bool colour = m.opts.keepColour && !frame.colour.empty();
  const cv::Mat& img = colour ? frame.colour : frame.grey;
  if (img.empty())
    throw std::runtime_error("rawlog recorder " + m.path + ": frame " + std::to_string(frame.index) +
                             " has no image" + (frame.origin.empty() ? "" : " (" + frame.origin + ")"));

  auto obs = mrpt::obs::CObservationImage::Create();
  obs->sensorLabel = m.opts.sensorLabel;
  obs->timestamp = mrpt::Clock::fromDouble(frame.timestamp);
  if (frame.camera)
  {
    if (frame.camera.get() != m.lastCam)
    {
      m.lastCam = frame.camera.get();
      m.lastTCam = camera::toTCamera(*frame.camera).value_or(mrpt::img::TCamera());
    }
    obs->cameraParams = m.lastTCam;
  }
  else
    obs->cameraParams = mrpt::img::TCamera();  // zero focal length: "no calibration" for readers

  if (m.opts.embedImages)
    obs->image = mrpt::img::CImage(img, mrpt::img::SHALLOW_COPY);
  else
  {
    char name[64];
    std::snprintf(name, sizeof(name), "%s_%06zu.png",
                  mrpt::system::fileNameStripInvalidChars(m.opts.sensorLabel).c_str(), m.frames);
    const std::string file = (fs::path(m.imagesDir) / name).string();
    bool ok = false;
    try
    {
      ok = cv::imwrite(file, img);
    }
    catch (const std::exception& e)
    {
      throw std::runtime_error("rawlog recorder: cannot write image " + file + ": " +
                               detail::oneLine(e.what()));
    }
    if (!ok) throw std::runtime_error("rawlog recorder: cannot write image " + file);
    obs->image.setExternalStorage(m.imagesPrefix + name);
  }
  m.writeObject(*obs);
  ++m.frames;
}

void CRawlogRecorder::recordObject(const mrpt::serialization::CSerializable& obj)
{
  Impl& m = *m_impl;
  m.requireOpen("recordObject()");
  m.writeObject(obj);
  ++m.objects;
}

void CRawlogRecorder::close()
{
  Impl& m = *m_impl;
  if (!m.open) return;
  m.open = false;
  m.arch.reset();
  m.file.close();
}

bool CRawlogRecorder::isOpen() const { return m_impl->open; }
const std::string& CRawlogRecorder::path() const { return m_impl->path; }
const TRecorderOptions& CRawlogRecorder::options() const { return m_impl->opts; }
std::size_t CRawlogRecorder::framesRecorded() const { return m_impl->frames; }
std::size_t CRawlogRecorder::objectsRecorded() const { return m_impl->objects; }
}  // namespace immslam::io
