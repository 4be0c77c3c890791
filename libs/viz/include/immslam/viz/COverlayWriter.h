/* imm-monoslam — writes overlay images to a folder (frame_%06d.png) and/or an MJPG video. */
#pragma once

#include <opencv2/core.hpp>

#include <memory>
#include <string>

namespace immslam::viz
{
/** Writes per-frame overlays (e.g. from drawOverlay()).
 *
 * Usage: `COverlayWriter w({"out/overlays", "out/overlays.avi", 5}); w.write(k, img);` for every
 * frame k; only frames with k % everyN == 0 are written. The video is opened at the first written
 * frame with that frame's size (later frames of another size are resized to it) and closed by
 * close() or the destructor. */
class COverlayWriter
{
 public:
  /** What to write. */
  struct TOptions
  {
    std::string folder;     ///< PNG folder (created); empty: no PNGs
    std::string videoPath;  ///< .avi file (MJPG); empty: no video
    int everyN = 1;         ///< write frames whose index is a multiple of this (>= 1)
    double videoFps = 15;   ///< frame rate stored in the video
    std::string pattern = "frame_%06d.png";  ///< printf pattern of PNG names (one integer)
  };

  /** \throws std::runtime_error if everyN < 1, the fps is not positive, the pattern is not a
   * single-integer printf pattern, or the folder cannot be created (names it). */
  explicit COverlayWriter(const TOptions& options);
  ~COverlayWriter();
  COverlayWriter(const COverlayWriter&) = delete;
  COverlayWriter& operator=(const COverlayWriter&) = delete;

  /** Writes frame `frameIndex` if it is selected by everyN.
   * \return true if something was written.
   * \throws std::runtime_error naming the file if a PNG or the video cannot be written. */
  bool write(long frameIndex, const cv::Mat& bgr);

  /** Finishes the video (also done by the destructor). */
  void close();

  /** Path of the PNG written for a frame index (whether or not it was written). */
  std::string pngPath(long frameIndex) const;

  /** Frames written so far. */
  long framesWritten() const { return m_written; }

 private:
  TOptions m_opts;
  std::string m_longPattern;  ///< the pattern with a "%ld" conversion
  struct TVideo;
  std::unique_ptr<TVideo> m_video;
  long m_written = 0;
};
}  // namespace immslam::viz
