/* imm-monoslam — one interface for every image stream (dataset folder, rawlog, live grabber,
 * built-in renderer): the estimator never knows where frames come from. */
#pragma once

#include <immslam/camera/CCameraModel.h>
#include <immslam/core/TTrajectory.h>

#include <opencv2/core/mat.hpp>

#include <memory>
#include <optional>
#include <string>

namespace immslam::io
{
/** One input frame. */
struct TFrame
{
  /** The input frame's own time in seconds (rgb.txt, rawlog timestamp, or index/fps). */
  double timestamp = 0;
  /** 0-based position in the input stream (counts skipped entries too). */
  std::size_t index = 0;
  /** 8-bit grey image (CV_8UC1): what the estimator uses. */
  cv::Mat grey;
  /** The original colour image (CV_8UC3, BGR) when the source is colour, else empty. */
  cv::Mat colour;
  /** Calibration attached to this frame by the source (rawlog cameraParams), may be null. */
  camera::CCameraModel::Ptr camera;
  /** Where it came from, for messages: "rgb/000012.png", "rawlog entry 57". */
  std::string origin;
};

/** Outcome of CImageSource::next(). */
enum class ENextStatus
{
  Frame,    ///< `frame` holds a new frame
  Skipped,  ///< an entry was unusable (missing/unreadable image, other observation type): `why` says
  End       ///< end of stream (or clean stop at a truncated/corrupted file: `why` says)
};

/** A stream of frames. Implementations never throw from next() for bad *content* (they skip or end
 * with a reason); they throw std::runtime_error from their constructor when the source cannot be
 * opened at all, naming the file.
 *
 * Implementations: CDatasetFolderSource (CDatasetFolderSource.h), CRawlogSource (CRawlogSource.h).
 * A live grabber fits the same interface (next() blocks until a frame arrives, sizeHint() 0,
 * calibration() from its configuration). */
class CImageSource
{
 public:
  using Ptr = std::unique_ptr<CImageSource>;
  virtual ~CImageSource() = default;

  /** Fetches the next frame. \param why on Skipped/End, a human-readable reason ("" on normal end). */
  virtual ENextStatus next(TFrame& frame, std::string& why) = 0;

  /** Calibration known before reading frames (calib.txt, first rawlog observation), or null. */
  virtual camera::CCameraModel::Ptr calibration() const { return nullptr; }

  /** Ground-truth camera trajectory T_W_C, when the source has one (groundtruth.txt, GT poses). */
  virtual std::optional<core::TTrajectory> groundTruth() const { return std::nullopt; }

  /** Short description for logs: "dataset folder ../shared/data/visp_rbt (99 frames)". */
  virtual std::string describe() const = 0;

  /** Number of entries if known in advance (for progress/ETA), else 0. */
  virtual std::size_t sizeHint() const { return 0; }

  /** True once next() has returned End because the input is damaged (truncated or corrupted file)
   * rather than at its normal end: the application then writes its outputs and exits with status 1. */
  virtual bool endedOnDamage() const { return false; }
};

/** Opens a dataset folder (../shared/data/README.md format), a video file (CVideoFileSource, by its
 * extension: isVideoFile()) or a .rawlog file (either MRPT layout; any other file), chosen by what
 * `path` is; `rawlogSensorLabel` picks a rawlog's camera (CRawlogSource; empty: its first).
 * \throws std::runtime_error naming the path if it is none of them or unreadable. */
CImageSource::Ptr openImageSource(const std::string& path, const std::string& rawlogSensorLabel = "");
}  // namespace immslam::io
