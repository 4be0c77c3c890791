/* imm-monoslam — writing frames (and raw MRPT observations) to a rawlog: `--record FILE.rawlog`. */
#pragma once

#include <immslam/io/CImageSource.h>

#include <memory>
#include <string>

namespace mrpt::serialization
{
class CSerializable;
}

namespace immslam::io
{
/** Options of CRawlogRecorder. */
struct TRecorderOptions
{
  /** true: pixels stored in the rawlog, losslessly (grey: raw bytes; colour: raw BGR, MRPT's JPEG
   * compression disabled while writing); false: one PNG file per frame in imagesDir, referenced
   * externally. */
  bool embedImages = true;
  /** Folder of the external images (embedImages = false); empty: `<rawlog dir>/<rawlog stem>_Images`
   * (MRPT's convention: rawlog-grabber, RawLogViewer and CRawlogSource find it). Created if needed. */
  std::string imagesDir;
  /** Sensor label of the written CObservationImage. */
  std::string sensorLabel = "CAMERA";
  /** false: only TFrame::grey is stored, even for colour frames. */
  bool keepColour = true;
  /** gzip compression level of the rawlog, 0 (none, fastest) .. 9. */
  int compressionLevel = 1;
};

/** Writes a gzip-compressed MRPT rawlog in the plain-observation layout (what rawlog-grabber
 * writes), readable by openImageSource() / CRawlogSource and MRPT's tools.
 *
 * record() writes one `CObservationImage` per frame: timestamp `mrpt::Clock::fromDouble(
 * frame.timestamp)` (100 ns resolution), image TFrame::colour (or TFrame::grey), `cameraParams` =
 * camera::toTCamera(*frame.camera) when the frame has a camera TCamera can represent (pinhole,
 * opencv), else empty. Reading the file back gives the same frames: identical pixels, timestamps
 * within 1e-7 s, the same calibration.
 *
 * recordObject() writes any MRPT object as is (CLiveCameraSource's raw mode).
 *
 * Embedded colour images need `CImage::DISABLE_JPEG_COMPRESSION`, a process-wide MRPT flag: it is
 * set for the duration of each write and restored; do not serialize colour CImages from another
 * thread meanwhile. Not thread-safe. */
class CRawlogRecorder
{
 public:
  /** Creates (overwrites) `path`.
   * \throws std::runtime_error naming the file (or images folder) if it cannot be created. */
  explicit CRawlogRecorder(const std::string& path, TRecorderOptions options = {});
  /** Closes the file (close()). */
  ~CRawlogRecorder();
  CRawlogRecorder(const CRawlogRecorder&) = delete;
  CRawlogRecorder& operator=(const CRawlogRecorder&) = delete;

  /** Appends one frame. \throws std::runtime_error naming the file on a write error, an empty
   * frame, or when closed. */
  void record(const TFrame& frame);

  /** Appends one MRPT object (an observation, a sensory frame, ...) unchanged.
   * \throws std::runtime_error naming the file on a write error or when closed. */
  void recordObject(const mrpt::serialization::CSerializable& obj);

  /** Flushes and closes the file (the gzip trailer is written; until then the file on disk is
   * an incomplete gzip stream, e.g. after a crash). Idempotent. MRPT's gzip stream reports no
   * error on closing. */
  void close();

  bool isOpen() const;
  const std::string& path() const;
  const TRecorderOptions& options() const;
  /** Frames written by record(). */
  std::size_t framesRecorded() const;
  /** Objects written by recordObject(). */
  std::size_t objectsRecorded() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};
}  // namespace immslam::io
