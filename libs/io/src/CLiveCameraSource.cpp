/* imm-monoslam — live image source over mrpt::hwdrivers::CCameraSensor. */
#include <immslam/camera/mrpt_camera.h>
#include <immslam/io/CLiveCameraSource.h>
#include <immslam/io/CRawlogRecorder.h>
#include <immslam/math/text.h>

#include "image_convert.h"
#include "observation_image.h"

#include <mrpt/config/CConfigFile.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/core/Clock.h>
#include <mrpt/hwdrivers/CCameraSensor.h>
#include <mrpt/img/CImage.h>
#include <mrpt/img/TCamera.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationImage.h>
#include <mrpt/obs/CObservationStereoImages.h>
#include <mrpt/serialization/CArchive.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <optional>
#include <sstream>
#include <stdexcept>

namespace fs = std::filesystem;

namespace immslam::io
{
namespace
{
/** The grabber types CCameraSensor::initialize() knows (MRPT 2.5.8). */
const std::vector<std::string>& knownGrabbers()
{
  static const std::vector<std::string> g = {"opencv", "dc1394", "bumblebee_dc1394", "ffmpeg",
                                             "rawlog", "swissranger", "kinect", "openni2",
                                             "image_dir", "flycap", "flycap_stereo", "svs",
                                             "duo3d", "myntd"};
  return g;
}

/** Keys read by CGenericSensor and CCameraSensor for the grabbers we check (lower case). */
bool isKnownKey(const std::string& key)
{
  static const std::vector<std::string> keys = {
      // CGenericSensor, rawlog-grabber
      "driver", "process_rate", "max_queue_len", "grab_decimation", "sensorlabel",
      "rawlog-grabber-ignore",
      // any grabber_type
      "grabber_type", "preview_decimation", "preview_reduction", "capture_grayscale",
      "external_images_format", "external_images_jpeg_quality", "external_images_own_thread",
      "external_images_own_thread_count", "pose_x", "pose_y", "pose_z", "pose_yaw", "pose_pitch",
      "pose_roll",
      // image_dir
      "image_dir_url", "left_format", "right_format", "start_index", "end_index"};
  static const std::vector<std::string> prefixes = {
      "cv_", "ffmpeg_", "rawlog_", "dc1394_", "bumblebee_", "svs_", "sr_", "kinect_",
      "flycap_", "fcs_", "myntd_", "duo3d_"};
  if (std::find(keys.begin(), keys.end(), key) != keys.end()) return true;
  for (const auto& p : prefixes)
    if (key.compare(0, p.size(), p) == 0) return true;
  return false;
}

/** A printf pattern with exactly one integer conversion ("img_%05d.png"), formatted safely. */
struct TIndexPattern
{
  std::string before, spec, after;  ///< spec: "%05d"

  /** \throws std::runtime_error (message without context) if the pattern is unusable. */
  static TIndexPattern parse(const std::string& pattern)
  {
    TIndexPattern p;
    int conversions = 0;
    std::string* out = &p.before;
    for (std::size_t i = 0; i < pattern.size(); ++i)
    {
      if (pattern[i] != '%')
      {
        *out += pattern[i];
        continue;
      }
      if (i + 1 < pattern.size() && pattern[i + 1] == '%')
      {
        *out += "%%";
        ++i;
        continue;
      }
      std::size_t j = i + 1;
      while (j < pattern.size() && std::string("-+ 0#").find(pattern[j]) != std::string::npos) ++j;
      while (j < pattern.size() && std::isdigit(static_cast<unsigned char>(pattern[j]))) ++j;
      if (j >= pattern.size() || std::string("diu").find(pattern[j]) == std::string::npos)
        throw std::runtime_error("'" + pattern + "' has a conversion other than an integer (%d, %05d, ...)");
      if (++conversions > 1)
        throw std::runtime_error("'" + pattern + "' has more than one conversion");
      p.spec = pattern.substr(i, j - i) + "d";
      out = &p.after;
      i = j;
    }
    if (conversions == 0)
      throw std::runtime_error("'" + pattern + "' has no integer conversion (e.g. img_%05d.png)");
    return p;
  }

  std::string format(int index) const
  {
    char buf[64];
    std::snprintf(buf, sizeof(buf), spec.c_str(), index);
    return unescape(before) + buf + unescape(after);
  }

  static std::string unescape(const std::string& s)
  {
    std::string o;
    for (std::size_t i = 0; i < s.size(); ++i)
    {
      o += s[i];
      if (s[i] == '%' && i + 1 < s.size() && s[i + 1] == '%') ++i;
    }
    return o;
  }
};

using detail::imageOf;
using detail::isEmptyCamera;
using detail::TImageView;

std::string cameraText(const camera::CCameraModel::Ptr& c)
{
  if (!c) return "none";
  return c->modelName() + " " + std::to_string(c->width()) + "x" + std::to_string(c->height());
}
}  // namespace

std::pair<std::string, std::string> splitLiveSpec(const std::string& spec)
{
  const auto pos = spec.rfind(':');
  if (pos != std::string::npos && pos + 1 < spec.size() && spec.find('/', pos) == std::string::npos)
    return {spec.substr(0, pos), spec.substr(pos + 1)};
  if (pos != std::string::npos && pos + 1 == spec.size()) return {spec.substr(0, pos), "CAMERA"};
  return {spec, "CAMERA"};
}

struct CLiveCameraSource::Impl
{
  std::string iniPath, section, where;  ///< where = "FILE [SECTION]" for messages
  TLiveOptions opts;
  ETimestampMode mode = ETimestampMode::Source;
  std::string grabber;
  std::string url;  ///< ffmpeg_url / image_dir_url / rawlog_file (resolved)
  bool ffmpegFile = false;
  bool greyOnly = false;
  std::size_t maxEmpty = 1;

  // image_dir bookkeeping (mirrors CCameraSensor's counter).
  std::optional<TIndexPattern> leftPattern, rightPattern;
  int startIndex = 0, endIndex = 100, imgDirNext = 0;
  std::string rawlogDir, rawlogImagesDir;

  std::unique_ptr<mrpt::hwdrivers::CCameraSensor> cam;
  /** Grabbed objects not yet returned by next(). */
  struct TPending
  {
    mrpt::obs::CObservation::Ptr obs;  ///< null for a non-observation object
    std::string origin;
  };
  std::deque<TPending> pending;
  std::size_t grabs = 0;        ///< non-empty grabs
  std::size_t nextIndex = 0;    ///< next TFrame::index
  std::size_t imageCount = 0;   ///< image observations met (FrameIndex time)
  std::size_t delivered = 0;
  bool ended = false;
  std::string endWhy;

  camera::CCameraModel::Ptr calib;
  std::optional<mrpt::img::TCamera> lastTCam;
  camera::CCameraModel::Ptr lastCam;
  bool sizeWarned = false, camWarned = false;
  std::vector<std::string> warnings;

  std::shared_ptr<CRawlogRecorder> recorder;
  ERecordMode recordMode = ERecordMode::Frames;

  std::string err(const std::string& what) const { return where + ": " + what; }

  /** A relative path as MRPT reads it (current directory), else relative to the ini's folder. */
  std::string resolvePath(const std::string& p) const
  {
    std::error_code ec;
    if (p.empty() || fs::path(p).is_absolute() || fs::exists(p, ec)) return p;
    const fs::path alt = fs::path(iniPath).parent_path() / p;
    return fs::exists(alt, ec) ? alt.string() : p;
  }

  void end(const std::string& why)
  {
    ended = true;
    endWhy = why;
    pending.clear();
    cam.reset();  // releases the device / file
  }

  /** Name of the image an image_dir grab reads at counter value `i`. */
  std::string imageDirPath(const TIndexPattern& p, int i) const
  {
    return (fs::path(url) / p.format(i)).string();
  }

  /** Why a grab threw, as an end-of-stream reason. */
  std::string endReason(const std::exception& e, bool eof) const
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

  /** One getNextFrame() call that yields something: queues the observations; false at the end
   * (end() called). Never throws. */
  bool grab(const std::atomic<bool>& stop)
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

  camera::CCameraModel::Ptr cameraOf(const mrpt::img::TCamera* c)
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

  /** Image pixels of a view: in memory, or an external file of a rawlog. */
  bool loadPixels(const mrpt::img::CImage& img, TFrame& f, std::string& why) const
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
};

CLiveCameraSource::CLiveCameraSource(const std::string& iniPath, const std::string& section,
                                     TLiveOptions options)
    : m_impl(std::make_unique<Impl>())
{
  Impl& m = *m_impl;
  m.iniPath = iniPath;
  m.section = section;
  m.opts = std::move(options);
  m.where = iniPath + " [" + section + "]";
  if (!(m.opts.frameRateHz > 0))
    throw std::runtime_error(m.err("frame rate must be > 0 (got " + std::to_string(m.opts.frameRateHz) + ")"));

  std::error_code ec;
  if (!fs::is_regular_file(iniPath, ec))
    throw std::runtime_error("live camera config not found: " + iniPath);

  // Read with MRPT's own parser, then copy into memory so that paths can be resolved.
  mrpt::config::CConfigFileMemory cfg;
  try
  {
    const mrpt::config::CConfigFile file(iniPath);
    std::vector<std::string> sections, keys;
    file.getAllSections(sections);
    // MRPT's ini parser compares section names case-insensitively.
    if (std::none_of(sections.begin(), sections.end(),
                     [&](const std::string& s) { return math::toLower(s) == math::toLower(section); }))
    {
      std::string list;
      for (const auto& s : sections) list += (list.empty() ? "" : ", ") + s;
      throw std::runtime_error("section [" + section + "] not found in " + iniPath +
                               (list.empty() ? " (it has no sections)" : " (sections: " + list + ")"));
    }
    for (const auto& s : sections)
    {
      file.getAllKeys(s, keys);
      for (const auto& k : keys) cfg.write(s, k, file.read_string(s, k, ""));
    }
  }
  catch (const std::runtime_error&)
  {
    throw;
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error("cannot read " + iniPath + ": " + detail::mrptMessage(e.what()));
  }

  // Keys.
  std::vector<std::string> keys;
  cfg.getAllKeys(section, keys);
  for (const auto& k : keys)
  {
    const std::string lk = math::toLower(k);
    if (lk == "left_filename_format" || lk == "right_filename_format")
      throw std::runtime_error(m.err("key '" + k + "' is not read by MRPT's CCameraSensor (its header " +
                                     "documents it, its code reads '" + lk.substr(0, lk.find('_')) +
                                     "_format'): rename it"));
    if (m.opts.strictKeys && !isKnownKey(lk))
      throw std::runtime_error(m.err("unknown key '" + k + "' (not read by MRPT's CCameraSensor)"));
  }
  m.grabber = math::toLower(math::trim(cfg.read_string(section, "grabber_type", "")));
  if (const auto sp = m.grabber.find_first_of(" \t"); sp != std::string::npos) m.grabber.resize(sp);
  if (m.grabber.empty())
    throw std::runtime_error(m.err("key grabber_type is missing (opencv, ffmpeg, image_dir, rawlog, ...)"));
  {
    const auto& g = knownGrabbers();
    if (std::find(g.begin(), g.end(), m.grabber) == g.end())
    {
      std::string list;
      for (const auto& s : g) list += (list.empty() ? "" : ", ") + s;
      throw std::runtime_error(m.err("unknown grabber_type '" + m.grabber + "' (known: " + list + ")"));
    }
  }
  m.greyOnly = cfg.read_bool(section, "capture_grayscale", false);
  if (m.greyOnly && m.grabber != "ffmpeg")
  {
    // CImage::grayscale() in MRPT 2.5.8 swaps red and blue (its SSSE3 path, taken when a row is a
    // multiple of 16 bytes: 320, 640 pixels wide...): convert here with OpenCV instead. The ffmpeg
    // grabber decodes straight to grey (swscale), which is right.
    cfg.write(section, "capture_grayscale", false);
  }
  if (cfg.read_int(section, "preview_decimation", 0) > 0)
  {
    cfg.write(section, "preview_decimation", 0);
    m.warnings.push_back(m.err("preview_decimation ignored: MRPT's preview window is never opened"));
  }

  // Grabber-specific checks (MRPT would fail later, or silently use a default).
  auto requireKey = [&](const std::string& key) {
    const std::string v = math::trim(cfg.read_string(section, key, ""));
    if (v.empty())
      throw std::runtime_error(m.err("key " + key + " is missing (needed by grabber_type = " + m.grabber + ")"));
    return v;
  };
  if (m.grabber == "ffmpeg")
  {
    m.url = requireKey("ffmpeg_url");
    m.ffmpegFile = m.url.find("://") == std::string::npos;
    if (m.ffmpegFile)
    {
      m.url = m.resolvePath(m.url);
      if (!fs::is_regular_file(m.url, ec))
        throw std::runtime_error(m.err("ffmpeg_url: video file not found: " + m.url));
      cfg.write(section, "ffmpeg_url", m.url);
    }
  }
  else if (m.grabber == "rawlog")
  {
    m.url = m.resolvePath(requireKey("rawlog_file"));
    if (!fs::is_regular_file(m.url, ec))
      throw std::runtime_error(m.err("rawlog_file: file not found: " + m.url));
    cfg.write(section, "rawlog_file", m.url);
    const fs::path p(m.url);
    m.rawlogDir = p.has_parent_path() ? p.parent_path().string() : std::string(".");
    m.rawlogImagesDir = (fs::path(m.rawlogDir) / (p.stem().string() + "_Images")).string();
  }
  else if (m.grabber == "image_dir")
  {
    m.url = m.resolvePath(requireKey("image_dir_url"));
    if (!fs::is_directory(m.url, ec))
      throw std::runtime_error(m.err("image_dir_url: folder not found: " + m.url));
    if (m.url.find('%') != std::string::npos)
      throw std::runtime_error(m.err("image_dir_url must not contain '%' (MRPT formats it): " + m.url));
    cfg.write(section, "image_dir_url", m.url);
    const std::string lf = math::trim(cfg.read_string(section, "left_format", ""));
    if (lf.empty())
      throw std::runtime_error(
          m.err("key left_format is missing (a printf pattern such as img_%05d.png; MRPT's default "
                "imL_%04d.jpg is not assumed)"));
    try
    {
      m.leftPattern = TIndexPattern::parse(lf);
    }
    catch (const std::exception& e)
    {
      throw std::runtime_error(m.err("left_format: " + std::string(e.what())));
    }
    const std::string rf = math::trim(cfg.read_string(section, "right_format", ""));
    if (!rf.empty())
    {
      try
      {
        m.rightPattern = TIndexPattern::parse(rf);
      }
      catch (const std::exception& e)
      {
        throw std::runtime_error(m.err("right_format: " + std::string(e.what())));
      }
    }
    m.startIndex = cfg.read_int(section, "start_index", 0);
    m.endIndex = cfg.read_int(section, "end_index", 100);
    if (m.endIndex < m.startIndex)
      throw std::runtime_error(m.err("end_index " + std::to_string(m.endIndex) + " < start_index " +
                                     std::to_string(m.startIndex)));
    m.imgDirNext = m.startIndex;
    const std::string first = m.imageDirPath(*m.leftPattern, m.startIndex);
    if (!fs::is_regular_file(first, ec))
      throw std::runtime_error(m.err("first image not found: " + first +
                                     " (image_dir_url, left_format, start_index)"));
  }

  m.mode = m.opts.timestampMode;
  if (m.mode == ETimestampMode::Auto)
    m.mode = (m.grabber == "image_dir" || m.grabber == "ffmpeg") ? ETimestampMode::FrameIndex
                                                                 : ETimestampMode::Source;
  m.maxEmpty = m.opts.maxEmptyGrabs > 0 ? m.opts.maxEmptyGrabs
               : (m.grabber == "ffmpeg" && !m.ffmpegFile) ? 50
                                                           : 1;

  // Open.
  m.cam = std::make_unique<mrpt::hwdrivers::CCameraSensor>();
  m.cam->setMinLoggingLevel(mrpt::system::LVL_ERROR);
  try
  {
    m.cam->loadConfig(cfg, section);
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error(m.err("MRPT's CCameraSensor rejected the section: " + detail::mrptMessage(e.what())));
  }
  try
  {
    m.cam->initialize();
  }
  catch (const std::exception& e)
  {
    std::string what = "grabber_type = " + m.grabber;
    if (m.grabber == "opencv")
      what += ", cv_camera_index = " + std::to_string(cfg.read_int(section, "cv_camera_index", 0));
    else if (!m.url.empty())
      what += ", " + m.url;
    throw std::runtime_error(m.err("cannot open the camera (" + what + "): " + detail::mrptMessage(e.what())));
  }

  // First frame: calibration and an early failure for sources that give nothing.
  if (!m.grab(m_stopRequested))
    throw std::runtime_error(m.err("no first frame from grabber_type = " + m.grabber + ": " + m.endWhy));
  for (const auto& p : m.pending)
  {
    if (!p.obs) continue;
    const TImageView v = imageOf(*p.obs);
    if (!v.image) continue;
    m.calib = m.cameraOf(v.camera);
    break;
  }
  if (!m.calib) m.calib = m.opts.camera;
}

CLiveCameraSource::~CLiveCameraSource() = default;

ENextStatus CLiveCameraSource::next(TFrame& frame, std::string& why)
{
  Impl& m = *m_impl;
  why.clear();
  try
  {
    if (m_stopRequested.load() && !m.ended) m.end("stopped by user");
    if (m.ended)
    {
      why = m.endWhy;
      return ENextStatus::End;
    }
    if (m.pending.empty() && !m.grab(m_stopRequested))
    {
      why = m.endWhy;
      return ENextStatus::End;
    }
    const mrpt::obs::CObservation::Ptr obs = m.pending.front().obs;
    const std::string origin = m.pending.front().origin;
    m.pending.pop_front();
    const std::size_t index = m.nextIndex++;

    auto recordRaw = [&](const mrpt::obs::CObservation& o) {
      if (m.recorder && m.recordMode == ERecordMode::RawObservations) m.recorder->recordObject(o);
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
    const std::size_t n = m.imageCount++;
    TFrame f;
    f.index = index;
    f.origin = origin;
    if (m.mode == ETimestampMode::FrameIndex)
      f.timestamp = double(n) / m.opts.frameRateHz;
    else if (obs->timestamp == INVALID_TIMESTAMP)
    {
      recordRaw(*obs);
      why = "observation without timestamp skipped (" + origin + ")";
      return ENextStatus::Skipped;
    }
    else
      f.timestamp = mrpt::Clock::toDouble(obs->timestamp);

    std::string sub;
    if (!m.loadPixels(*v.image, f, sub))
    {
      recordRaw(*obs);
      why = sub + " (" + origin + ")";
      return ENextStatus::Skipped;
    }
    if (m.greyOnly) f.colour.release();
    f.camera = m.cameraOf(v.camera);
    if (f.camera && !m.sizeWarned && (f.camera->width() != f.grey.cols || f.camera->height() != f.grey.rows))
    {
      m.sizeWarned = true;
      m.warnings.push_back("frame " + std::to_string(index) + " is " + std::to_string(f.grey.cols) + "x" +
                           std::to_string(f.grey.rows) + " but the calibration is " +
                           std::to_string(f.camera->width()) + "x" + std::to_string(f.camera->height()) +
                           " (frames are delivered anyway)");
    }

    if (m.recorder)
    {
      try
      {
        if (m.recordMode == ERecordMode::Frames)
          m.recorder->record(f);
        else
        {
          obs->timestamp = mrpt::Clock::fromDouble(f.timestamp);
          m.recorder->recordObject(*obs);
        }
      }
      catch (const std::exception& e)
      {
        m.end(std::string("recording failed: ") + e.what());
        why = m.endWhy;
        return ENextStatus::End;
      }
    }
    ++m.delivered;
    frame = std::move(f);
    return ENextStatus::Frame;
  }
  catch (const std::exception& e)
  {
    m.end("live capture error: " + detail::mrptMessage(e.what()));
    why = m.endWhy;
    return ENextStatus::End;
  }
}

camera::CCameraModel::Ptr CLiveCameraSource::calibration() const { return m_impl->calib; }

std::string CLiveCameraSource::describe() const
{
  const Impl& m = *m_impl;
  std::ostringstream s;
  s << "live camera " << m.where << ": grabber " << m.grabber;
  if (!m.url.empty()) s << " " << m.url;
  if (m.grabber == "image_dir")
    s << " (" << m.leftPattern->before << m.leftPattern->spec << m.leftPattern->after << ", "
      << m.startIndex << ".." << m.endIndex << ")";
  if (m.mode == ETimestampMode::FrameIndex)
    s << ", frame-index time at " << m.opts.frameRateHz << " Hz";
  else
    s << ", source timestamps";
  s << ", calibration " << cameraText(m.calib);
  if (m.calib) s << (m.calib == m.opts.camera ? " (given)" : " (from the observations)");
  return s.str();
}

std::size_t CLiveCameraSource::sizeHint() const
{
  const Impl& m = *m_impl;
  return m.grabber == "image_dir" ? std::size_t(m.endIndex - m.startIndex + 1) : 0;
}

void CLiveCameraSource::setRecorder(std::shared_ptr<CRawlogRecorder> recorder, ERecordMode mode)
{
  m_impl->recorder = std::move(recorder);
  m_impl->recordMode = mode;
}

const std::string& CLiveCameraSource::grabberType() const { return m_impl->grabber; }
ETimestampMode CLiveCameraSource::timestampMode() const { return m_impl->mode; }
const std::vector<std::string>& CLiveCameraSource::warnings() const { return m_impl->warnings; }
std::size_t CLiveCameraSource::framesDelivered() const { return m_impl->delivered; }
}  // namespace immslam::io
