/* imm-monoslam — CLiveCameraSource's grab loop and frames (see live_grabber.h). */
#include "live_grabber.h"

#include "image_convert.h"
#include "observation_image.h"

#include <immslam/camera/mrpt_camera.h>
#include <immslam/io/CRawlogRecorder.h>

#include <mrpt/core/Clock.h>
#include <mrpt/serialization/CArchive.h>

#include <chrono>
#include <filesystem>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace fs = std::filesystem;

namespace immslam::io
{
using detail::imageOf;
using detail::isEmptyCamera;
using detail::TImageView;

void CLiveCameraSource::Impl::resolveModes()
{
  mode = opts.timestampMode;
  if (mode == ETimestampMode::Auto)
    mode = (grabber == "image_dir" || grabber == "ffmpeg") ? ETimestampMode::FrameIndex : ETimestampMode::Source;
  maxEmpty = opts.maxEmptyGrabs > 0                  ? opts.maxEmptyGrabs
             : (grabber == "ffmpeg" && !ffmpegFile) ? 50
                                                     : 1;
}

void CLiveCameraSource::Impl::open(const mrpt::config::CConfigFileMemory& cfg)
{
  cam = std::make_unique<mrpt::hwdrivers::CCameraSensor>();
  cam->setMinLoggingLevel(mrpt::system::LVL_ERROR);
  try
  {
    cam->loadConfig(cfg, section);
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error(err("MRPT's CCameraSensor rejected the section: " + detail::mrptMessage(e.what())));
  }
  try
  {
    cam->initialize();
  }
  catch (const std::exception& e)
  {
    std::string what = "grabber_type = " + grabber;
    if (grabber == "opencv")
      what += ", cv_camera_index = " + std::to_string(cfg.read_int(section, "cv_camera_index", 0));
    else if (!url.empty())
      what += ", " + url;
    throw std::runtime_error(err("cannot open the camera (" + what + "): " + detail::mrptMessage(e.what())));
  }
}

void CLiveCameraSource::Impl::readFirstFrame(const std::atomic<bool>& stop)
{
  if (!grab(stop))
    throw std::runtime_error(err("no first frame from grabber_type = " + grabber + ": " + endWhy));
  for (const auto& p : pending)
  {
    if (!p.obs) continue;
    const TImageView v = imageOf(*p.obs);
    if (!v.image) continue;
    calib = cameraOf(v.camera);
    break;
  }
  if (!calib) calib = opts.camera;
}

void CLiveCameraSource::Impl::end(const std::string& why)
{
  ended = true;
  endWhy = why;
  pending.clear();
  cam.reset();  // releases the device / file
}

std::string CLiveCameraSource::Impl::endReason(const std::exception& e, bool eof) const
{
  const std::string msg = detail::mrptMessage(e.what());
  if (grabber == "rawlog")
    return eof ? "end of rawlog " + url : "rawlog " + url + ": read error: " + msg;
  if (grabber == "image_dir")
  {
    if (imgDirNext > endIndex)
      return "end of image sequence: index " + std::to_string(imgDirNext) + " > end_index " +
             std::to_string(endIndex);
    std::error_code ec;
    const std::string l = imageDirPath(*leftPattern, imgDirNext);
    if (!fs::exists(l, ec)) return "end of image sequence: no image " + l;
    if (rightPattern)
    {
      const std::string r = imageDirPath(*rightPattern, imgDirNext);
      if (!fs::exists(r, ec)) return "end of image sequence: no right image " + r;
    }
    return "end of image sequence: cannot read " + l + " (" + msg + ")";
  }
  if (grabber == "ffmpeg") return "ffmpeg " + url + ": cannot decode a frame (" + msg + ")";
  return "grabber " + grabber + " failed: " + msg;
}

bool CLiveCameraSource::Impl::grab(const std::atomic<bool>& stop)
{
  std::size_t empties = 0;
  while (!ended)
  {
    std::vector<mrpt::serialization::CSerializable::Ptr> out;
    try
    {
      cam->getNextFrame(out);
    }
    catch (const mrpt::serialization::CExceptionEOF& e)
    {
      end(endReason(e, true));
      return false;
    }
    catch (const std::exception& e)
    {
      end(endReason(e, false));
      return false;
    }
    if (stop.load())
    {
      end("stopped by user");
      return false;
    }
    bool any = false;
    for (auto& o : out)
    {
      if (!o) continue;  // grab_decimation: CCameraSensor returns a null pointer for a dropped grab
      auto obs = std::dynamic_pointer_cast<mrpt::obs::CObservation>(o);
      std::ostringstream origin;
      if (grabber == "image_dir")
        origin << "image_dir " << imageDirPath(*leftPattern, imgDirNext);
      else if (grabber == "ffmpeg" || grabber == "rawlog")
        origin << grabber << " " << url << ", grab " << grabs;
      else
        origin << grabber << " grab " << grabs;
      if (!obs) origin << " (class " << o->GetRuntimeClass()->className << ")";
      pending.push_back({obs, origin.str()});
      any = true;
    }
    // Every image_dir grab that returned (dropped or not) consumed one index.
    if (grabber == "image_dir" && !out.empty()) ++imgDirNext;
    if (any)
    {
      ++grabs;
      return true;
    }
    if (!out.empty()) continue;  // decimated grab
    if (++empties >= maxEmpty)
    {
      end(grabber == "ffmpeg" && ffmpegFile
              ? "end of video " + url
              : grabber + " gave no frame in " + std::to_string(empties) + " consecutive grabs");
      return false;
    }
  }
  return false;
}

camera::CCameraModel::Ptr CLiveCameraSource::Impl::cameraOf(const mrpt::img::TCamera* c)
{
  if (!c || isEmptyCamera(*c)) return opts.camera;
  if (lastTCam && *lastTCam == *c) return lastCam ? lastCam : opts.camera;
  lastTCam = *c;
  lastCam.reset();
  try
  {
    lastCam = camera::fromTCamera(*c);
  }
  catch (const std::exception& e)
  {
    if (!camWarned)
      warnings.push_back("observation calibration not usable (" + std::string(e.what()) +
                         "): using the given calibration");
    camWarned = true;
  }
  return lastCam ? lastCam : opts.camera;
}

bool CLiveCameraSource::Impl::loadPixels(const mrpt::img::CImage& img, TFrame& f, std::string& why) const
{
  if (!img.isExternallyStored()) return detail::setFrameImages(img.asCvMatRef(), f, why);
  // The rawlog grabber could not load it (MRPT looks only in <dir>/<stem>_Images or Images).
  const std::string name = img.getExternalStorageFile();
  if (fs::path(name).is_absolute()) return detail::loadFrameImages(name, f, why);
  std::error_code ec;
  for (const std::string& d : {rawlogImagesDir, rawlogDir})
  {
    const std::string file = (fs::path(d) / name).string();
    if (fs::is_regular_file(file, ec)) return detail::loadFrameImages(file, f, why);
  }
  why = "external image not found: " + name + " (looked in " + rawlogImagesDir + " and " +
        rawlogDir + ")";
  return false;
}

ENextStatus CLiveCameraSource::Impl::frameOf(const TPending& p, TFrame& frame, std::string& why)
{
  const mrpt::obs::CObservation::Ptr& obs = p.obs;
  const std::string& origin = p.origin;
  const std::size_t index = nextIndex++;

  auto recordRaw = [&](const mrpt::obs::CObservation& o) {
    if (recorder && recordMode == ERecordMode::RawObservations) recorder->recordObject(o);
  };
  const TImageView v = obs ? imageOf(*obs) : TImageView{};
  if (!v.image)
  {
    if (obs) recordRaw(*obs);
    why = (obs ? "observation of class " + std::string(obs->GetRuntimeClass()->className) +
                     " (label '" + obs->sensorLabel + "')"
               : std::string("non-observation object")) +
          " skipped (" + origin + ")";
    return ENextStatus::Skipped;
  }
  const std::size_t n = imageCount++;
  TFrame f;
  f.index = index;
  f.origin = origin;
  if (mode == ETimestampMode::FrameIndex)
    f.timestamp = double(n) / opts.frameRateHz;
  else if (obs->timestamp == INVALID_TIMESTAMP)
  {
    recordRaw(*obs);
    why = "observation without timestamp skipped (" + origin + ")";
    return ENextStatus::Skipped;
  }
  else
    f.timestamp = mrpt::Clock::toDouble(obs->timestamp);

  std::string sub;
  if (!loadPixels(*v.image, f, sub))
  {
    recordRaw(*obs);
    why = sub + " (" + origin + ")";
    return ENextStatus::Skipped;
  }
  if (greyOnly) f.colour.release();
  f.camera = cameraOf(v.camera);
  if (f.camera && !sizeWarned && (f.camera->width() != f.grey.cols || f.camera->height() != f.grey.rows))
  {
    sizeWarned = true;
    warnings.push_back("frame " + std::to_string(index) + " is " + std::to_string(f.grey.cols) + "x" +
                       std::to_string(f.grey.rows) + " but the calibration is " +
                       std::to_string(f.camera->width()) + "x" + std::to_string(f.camera->height()) +
                       " (frames are delivered anyway)");
  }
  if (recorder && !record(f, *obs))
  {
    why = endWhy;
    return ENextStatus::End;
  }
  ++delivered;
  frame = std::move(f);
  return ENextStatus::Frame;
}

bool CLiveCameraSource::Impl::record(const TFrame& f, mrpt::obs::CObservation& obs)
{
  try
  {
    if (recordMode == ERecordMode::Frames)
      recorder->record(f);
    else
    {
      obs.timestamp = mrpt::Clock::fromDouble(f.timestamp);
      recorder->recordObject(obs);
    }
  }
  catch (const std::exception& e)
  {
    end(std::string("recording failed: ") + e.what());
    return false;
  }
  return true;
}

void CLiveCameraSource::Impl::pace(double timestamp)
{
  const auto now = std::chrono::steady_clock::now();
  if (!paceOrigin)
  {
    paceOrigin.emplace(now, timestamp);
    return;
  }
  const auto due = paceOrigin->first + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                           std::chrono::duration<double>(timestamp - paceOrigin->second));
  if (due > now) std::this_thread::sleep_until(due);
}
}  // namespace immslam::io
