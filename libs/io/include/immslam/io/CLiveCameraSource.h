/* imm-monoslam — live capture through mrpt::hwdrivers::CCameraSensor as an image source
 * (program option `--live GRABBER.ini[:SECTION]`). */
#pragma once

#include <immslam/io/CImageSource.h>

#include <atomic>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace immslam::io
{
class CRawlogRecorder;

/** Which time a live frame gets (TFrame::timestamp). */
enum class ETimestampMode
{
  /** FrameIndex for `image_dir` and `ffmpeg` (their observations carry the wall-clock time of the
   * grab and the replay of a file must be deterministic), Source for every other grabber
   * (`rawlog` keeps the recorded times, devices the capture time). */
  Auto,
  /** The observation's own timestamp (`mrpt::Clock::toDouble`); an observation without a valid
   * timestamp is Skipped. */
  Source,
  /** \f$ t = n / f \f$, with n the 0-based count of image observations grabbed so far (equal to
   * TFrame::index when the grabber gives nothing but images) and f = TLiveOptions::frameRateHz.
   * Frames dropped by the section's `grab_decimation = k` are not counted: f is then the rate of
   * the delivered frames (the source rate / k). */
  FrameIndex
};

/** What CLiveCameraSource::setRecorder() writes. */
enum class ERecordMode
{
  /** One CObservationImage per delivered frame (CRawlogRecorder::record): reading the rawlog back
   * through openImageSource() gives the same frames (pixels, timestamps, calibration). */
  Frames,
  /** Every object the grabber returned, as rawlog-grabber would store it (stereo pairs, 3D scans,
   * IMU, ...), except that the observation a frame came from gets that frame's timestamp, so a
   * replay sees the times the estimator saw. Read back, monocular CObservationImage grabbers give
   * the same frames; other observation types are skipped by CRawlogSource. */
  RawObservations
};

/** Options of CLiveCameraSource. */
struct TLiveOptions
{
  /** See ETimestampMode. */
  ETimestampMode timestampMode = ETimestampMode::Auto;
  /** Nominal frame rate for ETimestampMode::FrameIndex, in Hz (> 0). */
  double frameRateHz = 30.0;
  /** Calibration used when the observations carry none (`image_dir`, `ffmpeg` and most devices:
   * their `cameraParams` is empty). The application passes its `--calib` or the config's camera.
   * May be null. */
  camera::CCameraModel::Ptr camera;
  /** Consecutive empty grabs (the ffmpeg grabber returns nothing on a read failure) that end the
   * stream; 0 = automatic: 1 when `ffmpeg_url` is a local file (an empty grab is its end of file),
   * 50 for a network stream (temporary failures are retried). */
  std::size_t maxEmptyGrabs = 0;
  /** Deliver each frame no earlier than its timestamp's distance from the first frame's (steady
   * clock, from the first delivery): a replay of files (`image_dir`, `ffmpeg` on a file, `rawlog`)
   * then comes at its recorded or nominal rate, as the camera would deliver it, to see how the
   * estimator keeps up in real time. A device delivers at its own rate either way. */
  bool paced = false;
  /** Reject keys of the section that neither CCameraSensor nor CGenericSensor reads (the MRPT ini
   * parser ignores them silently), naming them. Keys prefixed by another grabber's name
   * (`dc1394_`, `flycap_`, `kinect_`, ...) are always accepted. */
  bool strictKeys = true;
};

/** Live frames from any grabber of `mrpt::hwdrivers::CCameraSensor`, configured by a standard MRPT
 * sensor section (the one `rawlog-grabber` reads).
 *
 * Example sections, one file each (`--live usb_camera.ini`; a file may also hold several sections,
 * chosen by `--live FILE.ini:SECTION`):
 * \code
 * # usb_camera.ini: a USB camera (V4L2 /dev/video0) through OpenCV. Calibrate with --calib.
 * [CAMERA]
 * grabber_type     = opencv
 * cv_camera_index  = 0
 * cv_frame_width   = 640
 * cv_frame_height  = 480
 * # capture_grayscale = true
 *
 * # video_file.ini: a video file (or an rtsp:// / http:// stream) decoded by FFmpeg, until its end.
 * # Frames are timed index / 30 Hz (TLiveOptions::frameRateHz). Lossless or intra-only codecs
 * # (FFV1, MJPEG) give every frame; MRPT does not drain the decoder, so H.264 loses the last few.
 * [CAMERA]
 * grabber_type     = ffmpeg
 * ffmpeg_url       = videos/corridor.mkv
 *
 * # image_folder.ini: numbered images img_00000.png ... img_00499.png, timed index / 30 Hz.
 * # The key is left_format (MRPT's header documents left_filename_format, which MRPT ignores).
 * [CAMERA]
 * grabber_type     = image_dir
 * image_dir_url    = sequences/corridor
 * left_format      = img_%05d.png
 * start_index      = 0
 * end_index        = 499
 * \endcode
 * Relative paths (`ffmpeg_url`, `image_dir_url`, `rawlog_file`) are taken relative to the current
 * directory, as MRPT does, or else relative to the ini file's folder when they exist only there.
 *
 * Construction loads and checks the section (`grabber_type` is required; `image_dir` needs
 * `image_dir_url` and a `left_format` with exactly one integer conversion such as `%05d`;
 * `ffmpeg` needs `ffmpeg_url`; `rawlog` needs `rawlog_file`), calls `CCameraSensor::loadConfig`
 * and `initialize`, then grabs the first frame, so that calibration() is known and a source that
 * cannot deliver anything fails at once. The MRPT preview window (`preview_decimation`) is never
 * opened (a warning says so); MRPT's warnings are silenced, but its `initialize()` still prints a
 * few lines to std::cout.
 *
 * next() blocks until the grabber returns; it turns each observation into a frame:
 * `CObservationImage` (image), `CObservationStereoImages` (left image, `leftCamera`),
 * `CObservation3DRangeScan` with an intensity image (`cameraParamsIntensity`); other observation
 * types give Skipped. Pixels as in the other sources: TFrame::grey CV_8UC1, TFrame::colour kept
 * (BGR) for colour input; `capture_grayscale = true` gives grey frames only (converted by OpenCV:
 * MRPT 2.5.8's own conversion swaps red and blue for rows of a multiple of 16 bytes, so it is
 * bypassed; the ffmpeg grabber decodes straight to grey). TFrame::camera is the observation's
 * calibration when it carries one (`rawlog` grabber: camera::fromTCamera of a non-empty
 * `cameraParams`), else TLiveOptions::camera.
 * Frames whose size differs from the calibration are still delivered (warnings() notes it once).
 *
 * End of stream (next() returns End, `why` says which): the ffmpeg grabber's empty grab at end of
 * file ("end of video <url>"), the image_dir grabber's exception past `end_index` or at the first
 * missing image ("end of image sequence: ..."), the rawlog grabber's CExceptionEOF ("end of rawlog
 * <file>"), requestStop() ("stopped by user"), or any other grabber exception (its message).
 * No exception escapes next(). next() is not thread-safe; requestStop() is. */
class CLiveCameraSource : public CImageSource
{
 public:
  /** Opens the grabber described by section `section` of `iniPath`.
   * \throws std::runtime_error naming the file, section and key at fault: missing or unreadable
   * ini file, missing section, missing/unknown `grabber_type`, missing/malformed grabber keys,
   * unknown keys (TLiveOptions::strictKeys), a device or file that cannot be opened, a source that
   * gives no first frame. */
  explicit CLiveCameraSource(
      const std::string& iniPath, const std::string& section = "CAMERA", TLiveOptions options = {});
  ~CLiveCameraSource() override;
  CLiveCameraSource(const CLiveCameraSource&) = delete;
  CLiveCameraSource& operator=(const CLiveCameraSource&) = delete;

  ENextStatus next(TFrame& frame, std::string& why) override;
  /** The first observation's calibration when it carries one, else TLiveOptions::camera (may be
   * null). */
  camera::CCameraModel::Ptr calibration() const override;
  /** "live camera FILE [SECTION]: grabber image_dir /x (img_%05d.png, 0..99), frame-index time at
   * 30 Hz, pinhole camera from the options". */
  std::string describe() const override;
  /** `end_index - start_index + 1` for `image_dir`, else 0 (unknown). */
  std::size_t sizeHint() const override;

  /** Makes the next call of next() return End ("stopped by user"), also when called while next()
   * is blocked in the grabber (that frame is then dropped). Thread-safe and async-signal-safe (one
   * store to a lock-free std::atomic<bool>): a SIGINT handler may call it. */
  void requestStop() noexcept { m_stopRequested.store(true); }
  /** True once requestStop() was called. */
  bool stopRequested() const noexcept { return m_stopRequested.load(); }

  /** Records from now on what next() delivers (mode Frames) or grabs (mode RawObservations) to
   * `recorder` (null: stop recording). A recording error ends the stream (End, `why` names the
   * file). */
  void setRecorder(std::shared_ptr<CRawlogRecorder> recorder, ERecordMode mode = ERecordMode::Frames);

  /** The `grabber_type` of the section (lower case). */
  const std::string& grabberType() const;
  /** The time mode in force (Auto resolved). */
  ETimestampMode timestampMode() const;
  /** Non-fatal remarks: ignored preview, frame size differing from the calibration, ... */
  const std::vector<std::string>& warnings() const;
  /** Frames delivered so far. */
  std::size_t framesDelivered() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
  std::atomic<bool> m_stopRequested{false};
  static_assert(std::atomic<bool>::is_always_lock_free, "requestStop() must be async-signal-safe");
};

/** Splits the argument of `--live GRABBER.ini[:SECTION]` into (file, section): the text after the
 * last ':' is the section when it is non-empty and holds no '/' (so "a:b/c.ini" is a file); the
 * section defaults to `CAMERA`. */
std::pair<std::string, std::string> splitLiveSpec(const std::string& spec);
}  // namespace immslam::io
