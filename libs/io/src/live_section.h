/* imm-monoslam — private to libs/io: the grabber section of a `--live` ini file, read and checked
 * before MRPT's CCameraSensor gets it (CLiveCameraSource). */
#pragma once

#include <mrpt/config/CConfigFileMemory.h>

#include <optional>
#include <string>
#include <vector>

namespace immslam::io::detail
{
/** A printf pattern with exactly one integer conversion ("img_%05d.png"), formatted safely. */
struct TIndexPattern
{
  std::string before, spec, after;  ///< spec: "%05d"

  /** \throws std::runtime_error (message without context) if the pattern is unusable. */
  static TIndexPattern parse(const std::string& pattern);
  /** The file name for counter value `index`. */
  std::string format(int index) const;
  /** `s` with every "%%" turned into "%". */
  static std::string unescape(const std::string& s);
};

/** What CLiveCameraSource knows of its grabber section beside MRPT's CCameraSensor: the grabber, the
 * file or folder it reads (resolved), the image_dir counter range. */
struct TLiveSection
{
  std::string iniPath, section, where;  ///< where = "FILE [SECTION]" for messages
  std::string grabber;                  ///< grabber_type, lower case
  std::string url;                      ///< ffmpeg_url / image_dir_url / rawlog_file (resolved)
  bool ffmpegFile = false;              ///< ffmpeg_url is a local file (no "://")
  bool greyOnly = false;                ///< capture_grayscale (converted by us, not by MRPT)
  std::optional<TIndexPattern> leftPattern, rightPattern;  ///< image_dir: left_format, right_format
  int startIndex = 0, endIndex = 100;                       ///< image_dir: start_index, end_index
  std::string rawlogDir, rawlogImagesDir;                   ///< rawlog: where external images may be
  std::vector<std::string> warnings;                        ///< non-fatal remarks

  /** "FILE [SECTION]: what". */
  std::string err(const std::string& what) const { return where + ": " + what; }
  /** A relative path as MRPT reads it (current directory), else relative to the ini's folder. */
  std::string resolvePath(const std::string& p) const;
  /** Name of the image an image_dir grab reads at counter value `i`. */
  std::string imageDirPath(const TIndexPattern& p, int i) const;
};

/** Reads the file `s.iniPath` (every section, with MRPT's own parser) into `cfg` and checks section
 * `s.section` (`s.iniPath`, `s.section` and `s.where` are set by the caller): known keys (with
 * `strictKeys`), `grabber_type`, and the keys and files of the ffmpeg, rawlog and image_dir
 * grabbers; fills the other fields of `s`. `cfg` is left as CCameraSensor must get it: paths
 * resolved, `capture_grayscale` off except for ffmpeg (grey conversion by OpenCV, see
 * CLiveCameraSource), `preview_decimation` 0 (with a warning).
 * \throws std::runtime_error naming the file, section and key at fault. */
void loadLiveSection(TLiveSection& s, mrpt::config::CConfigFileMemory& cfg, bool strictKeys);
}  // namespace immslam::io::detail
