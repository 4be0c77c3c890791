/* imm-monoslam — writes a dataset folder (../shared/data/README.md format). */
#pragma once

#include <immslam/camera/CCameraModel.h>
#include <immslam/core/TTrajectory.h>

#include <opencv2/core/mat.hpp>

#include <fstream>
#include <string>

namespace immslam::io
{
/** Writes `rgb/NNNNNN.png`, `rgb.txt`, `calib.txt` and (when poses are given) `groundtruth.txt`
 * into a folder (created; existing files overwritten). Extra per-dataset files are the caller's.
 * Usage: construct, addFrame() per frame, then close() (also called by the destructor). */
class CDatasetWriter
{
 public:
  /** \param comment a line written as the first '#' comment of rgb.txt and groundtruth.txt. */
  CDatasetWriter(const std::string& folder, const camera::CCameraModel& cam, const std::string& comment = {});
  ~CDatasetWriter();

  /** Writes one image (grey or BGR) as rgb/NNNNNN.png and its rgb.txt line; if `gt` is given, the
   * groundtruth.txt line (timestamp of the frame). \return the relative path written. */
  std::string addFrame(double timestamp, const cv::Mat& image, const core::TStampedPose* gt = nullptr);

  /** Flushes and closes the text files. */
  void close();

  const std::string& folder() const { return m_folder; }
  std::size_t frameCount() const { return m_count; }

 private:
  std::string m_folder;
  std::ofstream m_rgb, m_gt;
  std::size_t m_count = 0;
  bool m_gtOpen = false;
  std::string m_comment;
};
}  // namespace immslam::io
