/* imm-monoslam — the grabber section of CLiveCameraSource, read and checked (see live_section.h). */
#include "live_section.h"

#include "image_convert.h"

#include <immslam/math/text.h>

#include <mrpt/config/CConfigFile.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

namespace fs = std::filesystem;

namespace immslam::io::detail
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

/** The whole ini file into `cfg`, read with MRPT's own parser (then copied into memory so that
 * paths can be resolved); the section must exist. */
void readIniFile(const TLiveSection& s, mrpt::config::CConfigFileMemory& cfg)
{
  std::error_code ec;
  if (!fs::is_regular_file(s.iniPath, ec))
    throw std::runtime_error("live camera config not found: " + s.iniPath);
  try
  {
    const mrpt::config::CConfigFile file(s.iniPath);
    std::vector<std::string> sections, keys;
    file.getAllSections(sections);
    // MRPT's ini parser compares section names case-insensitively.
    if (std::none_of(sections.begin(), sections.end(),
                     [&](const std::string& n) { return math::toLower(n) == math::toLower(s.section); }))
    {
      std::string list;
      for (const auto& n : sections) list += (list.empty() ? "" : ", ") + n;
      throw std::runtime_error("section [" + s.section + "] not found in " + s.iniPath +
                               (list.empty() ? " (it has no sections)" : " (sections: " + list + ")"));
    }
    for (const auto& n : sections)
    {
      file.getAllKeys(n, keys);
      for (const auto& k : keys) cfg.write(n, k, file.read_string(n, k, ""));
    }
  }
  catch (const std::runtime_error&)
  {
    throw;
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error("cannot read " + s.iniPath + ": " + mrptMessage(e.what()));
  }
}

/** Keys MRPT would ignore silently: the misnamed left/right_filename_format always, any unknown
 * key with `strictKeys`. */
void checkKeys(const TLiveSection& s, const mrpt::config::CConfigFileMemory& cfg, bool strictKeys)
{
  std::vector<std::string> keys;
  cfg.getAllKeys(s.section, keys);
  for (const auto& k : keys)
  {
    const std::string lk = math::toLower(k);
    if (lk == "left_filename_format" || lk == "right_filename_format")
      throw std::runtime_error(s.err("key '" + k + "' is not read by MRPT's CCameraSensor (its header " +
                                     "documents it, its code reads '" + lk.substr(0, lk.find('_')) +
                                     "_format'): rename it"));
    if (strictKeys && !isKnownKey(lk))
      throw std::runtime_error(s.err("unknown key '" + k + "' (not read by MRPT's CCameraSensor)"));
  }
}

/** grabber_type: required, one of knownGrabbers(). */
std::string readGrabberType(const TLiveSection& s, const mrpt::config::CConfigFileMemory& cfg)
{
  std::string grabber = math::toLower(math::trim(cfg.read_string(s.section, "grabber_type", "")));
  if (const auto sp = grabber.find_first_of(" \t"); sp != std::string::npos) grabber.resize(sp);
  if (grabber.empty())
    throw std::runtime_error(s.err("key grabber_type is missing (opencv, ffmpeg, image_dir, rawlog, ...)"));
  const auto& g = knownGrabbers();
  if (std::find(g.begin(), g.end(), grabber) == g.end())
  {
    std::string list;
    for (const auto& n : g) list += (list.empty() ? "" : ", ") + n;
    throw std::runtime_error(s.err("unknown grabber_type '" + grabber + "' (known: " + list + ")"));
  }
  return grabber;
}

/** The value of a key the grabber needs (trimmed, non-empty). */
std::string requireKey(const TLiveSection& s, const mrpt::config::CConfigFileMemory& cfg, const std::string& key)
{
  const std::string v = math::trim(cfg.read_string(s.section, key, ""));
  if (v.empty())
    throw std::runtime_error(s.err("key " + key + " is missing (needed by grabber_type = " + s.grabber + ")"));
  return v;
}

/** ffmpeg: ffmpeg_url, a local file that exists (resolved) or a stream URL. */
void checkFfmpeg(TLiveSection& s, mrpt::config::CConfigFileMemory& cfg)
{
  s.url = requireKey(s, cfg, "ffmpeg_url");
  s.ffmpegFile = s.url.find("://") == std::string::npos;
  if (!s.ffmpegFile) return;
  s.url = s.resolvePath(s.url);
  std::error_code ec;
  if (!fs::is_regular_file(s.url, ec))
    throw std::runtime_error(s.err("ffmpeg_url: video file not found: " + s.url));
  cfg.write(s.section, "ffmpeg_url", s.url);
}

/** rawlog: rawlog_file exists (resolved); the folders of its external images. */
void checkRawlog(TLiveSection& s, mrpt::config::CConfigFileMemory& cfg)
{
  s.url = s.resolvePath(requireKey(s, cfg, "rawlog_file"));
  std::error_code ec;
  if (!fs::is_regular_file(s.url, ec))
    throw std::runtime_error(s.err("rawlog_file: file not found: " + s.url));
  cfg.write(s.section, "rawlog_file", s.url);
  const fs::path p(s.url);
  s.rawlogDir = p.has_parent_path() ? p.parent_path().string() : std::string(".");
  s.rawlogImagesDir = (fs::path(s.rawlogDir) / (p.stem().string() + "_Images")).string();
}

/** An image_dir pattern key, parsed; the error names the key. */
TIndexPattern parsePatternKey(const TLiveSection& s, const std::string& key, const std::string& value)
{
  try
  {
    return TIndexPattern::parse(value);
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error(s.err(key + ": " + std::string(e.what())));
  }
}

/** image_dir: the folder (resolved), left_format (and right_format), the index range, the first image. */
void checkImageDir(TLiveSection& s, mrpt::config::CConfigFileMemory& cfg)
{
  std::error_code ec;
  s.url = s.resolvePath(requireKey(s, cfg, "image_dir_url"));
  if (!fs::is_directory(s.url, ec))
    throw std::runtime_error(s.err("image_dir_url: folder not found: " + s.url));
  if (s.url.find('%') != std::string::npos)
    throw std::runtime_error(s.err("image_dir_url must not contain '%' (MRPT formats it): " + s.url));
  cfg.write(s.section, "image_dir_url", s.url);
  const std::string lf = math::trim(cfg.read_string(s.section, "left_format", ""));
  if (lf.empty())
    throw std::runtime_error(
        s.err("key left_format is missing (a printf pattern such as img_%05d.png; MRPT's default "
              "imL_%04d.jpg is not assumed)"));
  s.leftPattern = parsePatternKey(s, "left_format", lf);
  const std::string rf = math::trim(cfg.read_string(s.section, "right_format", ""));
  if (!rf.empty()) s.rightPattern = parsePatternKey(s, "right_format", rf);
  s.startIndex = cfg.read_int(s.section, "start_index", 0);
  s.endIndex = cfg.read_int(s.section, "end_index", 100);
  if (s.endIndex < s.startIndex)
    throw std::runtime_error(s.err("end_index " + std::to_string(s.endIndex) + " < start_index " +
                                   std::to_string(s.startIndex)));
  const std::string first = s.imageDirPath(*s.leftPattern, s.startIndex);
  if (!fs::is_regular_file(first, ec))
    throw std::runtime_error(s.err("first image not found: " + first +
                                   " (image_dir_url, left_format, start_index)"));
}
}  // namespace

TIndexPattern TIndexPattern::parse(const std::string& pattern)
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

std::string TIndexPattern::format(int index) const
{
  char buf[64];
  std::snprintf(buf, sizeof(buf), spec.c_str(), index);
  return unescape(before) + buf + unescape(after);
}

std::string TIndexPattern::unescape(const std::string& s)
{
  std::string o;
  for (std::size_t i = 0; i < s.size(); ++i)
  {
    o += s[i];
    if (s[i] == '%' && i + 1 < s.size() && s[i + 1] == '%') ++i;
  }
  return o;
}

std::string TLiveSection::resolvePath(const std::string& p) const
{
  std::error_code ec;
  if (p.empty() || fs::path(p).is_absolute() || fs::exists(p, ec)) return p;
  const fs::path alt = fs::path(iniPath).parent_path() / p;
  return fs::exists(alt, ec) ? alt.string() : p;
}

std::string TLiveSection::imageDirPath(const TIndexPattern& p, int i) const
{
  return (fs::path(url) / p.format(i)).string();
}

void loadLiveSection(TLiveSection& s, mrpt::config::CConfigFileMemory& cfg, bool strictKeys)
{
  readIniFile(s, cfg);
  checkKeys(s, cfg, strictKeys);
  s.grabber = readGrabberType(s, cfg);
  s.greyOnly = cfg.read_bool(s.section, "capture_grayscale", false);
  if (s.greyOnly && s.grabber != "ffmpeg")
  {
    // CImage::grayscale() in MRPT 2.5.8 swaps red and blue (its SSSE3 path, taken when a row is a
    // multiple of 16 bytes: 320, 640 pixels wide...): convert here with OpenCV instead. The ffmpeg
    // grabber decodes straight to grey (swscale), which is right.
    cfg.write(s.section, "capture_grayscale", false);
  }
  if (cfg.read_int(s.section, "preview_decimation", 0) > 0)
  {
    cfg.write(s.section, "preview_decimation", 0);
    s.warnings.push_back(s.err("preview_decimation ignored: MRPT's preview window is never opened"));
  }
  // Grabber-specific checks (MRPT would fail later, or silently use a default).
  if (s.grabber == "ffmpeg")
    checkFfmpeg(s, cfg);
  else if (s.grabber == "rawlog")
    checkRawlog(s, cfg);
  else if (s.grabber == "image_dir")
    checkImageDir(s, cfg);
}
}  // namespace immslam::io::detail
