/* imm-monoslam — image source reading a dataset folder (../shared/data/README.md format). */
#pragma once

#include <immslam/io/CImageSource.h>

#include <iosfwd>
#include <string>
#include <vector>

namespace immslam::io
{
/** One line of rgb.txt (comments and blank lines are not entries). */
struct TDatasetEntry
{
  /** Timestamp in seconds (first field). */
  double timestamp = 0;
  /** Image path as written in rgb.txt (relative to the folder, or absolute). */
  std::string path;
  /** 1-based line number in rgb.txt. */
  std::size_t line = 0;
  /** Empty for a well-formed line, else why the line is malformed ("rgb.txt:7: ..."). */
  std::string error;
};

/** Reads a dataset folder: `rgb.txt` (`timestamp path` per line, `#` comments), optional
 * `calib.txt` (camera::loadCalibFile) and optional `groundtruth.txt` (TUM, core::readTumTrajectory).
 *
 * rgb.txt, calib.txt and groundtruth.txt are parsed in the constructor; images are decoded lazily
 * by next() with `cv::imread(IMREAD_UNCHANGED)`:
 * - 8-bit grey images give TFrame::grey and an empty TFrame::colour;
 * - colour images (BGR, BGRA) keep TFrame::colour (BGR) and are converted to grey by cv::cvtColor;
 * - 16-bit images are scaled to 8 bits (value / 256).
 *
 * A malformed rgb.txt line, a missing or undecodable image file give ENextStatus::Skipped with a
 * reason naming `rgb.txt:LINE` or the image file; next() never throws for bad content.
 * Every frame carries calibration() (may be null) in TFrame::camera. */
class CDatasetFolderSource : public CImageSource
{
 public:
  /** Opens `folder`.
   * \throws std::runtime_error naming the path if the folder or its rgb.txt cannot be read, if
   * rgb.txt lists no frame (empty or only comments: an empty input is an error, not an empty run),
   * or if calib.txt / groundtruth.txt exist but are malformed (their loaders name file and line). */
  explicit CDatasetFolderSource(const std::string& folder);

  ENextStatus next(TFrame& frame, std::string& why) override;
  camera::CCameraModel::Ptr calibration() const override { return m_calib; }
  std::optional<core::TTrajectory> groundTruth() const override { return m_gt; }
  std::string describe() const override;
  /** Number of rgb.txt entries (malformed lines included: each gives one next() result). */
  std::size_t sizeHint() const override { return m_entries.size(); }

  /** The parsed rgb.txt entries, in file order. */
  const std::vector<TDatasetEntry>& entries() const { return m_entries; }
  /** The folder as given to the constructor. */
  const std::string& folder() const { return m_folder; }
  /** Absolute-or-folder-relative path of an entry's image, as opened by next(). */
  std::string imagePath(const TDatasetEntry& e) const;
  /** Continues the stream at entry `index` (0-based rgb.txt entry; past the end: End). */
  void seek(std::size_t index) { m_cursor = index; }

 private:
  std::string m_folder;
  std::string m_rgbTxt;
  std::vector<TDatasetEntry> m_entries;
  camera::CCameraModel::Ptr m_calib;
  std::optional<core::TTrajectory> m_gt;
  std::size_t m_cursor = 0;
};

/** Parses the text of an rgb.txt file. Malformed lines become entries with TDatasetEntry::error set
 * (never a throw). \param fileLabel used in error texts, e.g. "data/x/rgb.txt". */
std::vector<TDatasetEntry> parseRgbTxt(std::istream& in, const std::string& fileLabel);
}  // namespace immslam::io
