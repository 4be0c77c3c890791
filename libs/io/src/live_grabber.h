/* imm-monoslam — private to libs/io: the state of a CLiveCameraSource (its pimpl): MRPT's
 * CCameraSensor, the grab loop, end-of-stream reasons and the turning of observations into frames. */
#pragma once

#include <immslam/io/CLiveCameraSource.h>

#include "live_section.h"

#include <mrpt/hwdrivers/CCameraSensor.h>
#include <mrpt/img/CImage.h>
#include <mrpt/img/TCamera.h>
#include <mrpt/obs/CObservation.h>

#include <atomic>
#include <chrono>
#include <deque>
#include <exception>
#include <memory>
#include <optional>
#include <string>
#include <utility>

namespace immslam::io
{
/** The grabber section (TLiveSection: grabber, paths, image_dir range, warnings) and everything
 * that changes while frames are grabbed. */
struct CLiveCameraSource::Impl : detail::TLiveSection
{
  TLiveOptions opts;
  ETimestampMode mode = ETimestampMode::Source;  ///< Auto resolved
  std::size_t maxEmpty = 1;                      ///< consecutive empty grabs that end the stream
  int imgDirNext = 0;  ///< image_dir: the index of the next grab (mirrors CCameraSensor's counter)

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
  /** TLiveOptions::paced: the steady-clock time and the timestamp of the first frame delivered. */
  std::optional<std::pair<std::chrono::steady_clock::time_point, double>> paceOrigin;
  bool ended = false;
  std::string endWhy;

  camera::CCameraModel::Ptr calib;
  std::optional<mrpt::img::TCamera> lastTCam;
  camera::CCameraModel::Ptr lastCam;
  bool sizeWarned = false, camWarned = false;

  std::shared_ptr<CRawlogRecorder> recorder;
  ERecordMode recordMode = ERecordMode::Frames;

  /** The time mode (Auto resolved) and the empty-grab limit, from the options and the grabber. */
  void resolveModes();
  /** CCameraSensor::loadConfig(cfg) and initialize(). \throws std::runtime_error naming the section. */
  void open(const mrpt::config::CConfigFileMemory& cfg);
  /** Grabs the first frame and takes its calibration (else TLiveOptions::camera).
   * \throws std::runtime_error when the grabber gives nothing. */
  void readFirstFrame(const std::atomic<bool>& stop);

  /** Ends the stream with a reason; releases the device or file. */
  void end(const std::string& why);
  /** Why a grab threw, as an end-of-stream reason. */
  std::string endReason(const std::exception& e, bool eof) const;
  /** One getNextFrame() call that yields something: queues the observations; false at the end
   * (end() called). Never throws. */
  bool grab(const std::atomic<bool>& stop);
  /** The calibration of an observation (cached), else TLiveOptions::camera. */
  camera::CCameraModel::Ptr cameraOf(const mrpt::img::TCamera* c);
  /** Image pixels of a view: in memory, or an external file of a rawlog. */
  bool loadPixels(const mrpt::img::CImage& img, TFrame& f, std::string& why) const;
  /** The frame of a grabbed object (next() after the queue): Frame, Skipped (with `why`), or End
   * when recording fails. */
  ENextStatus frameOf(const TPending& p, TFrame& frame, std::string& why);
  /** TLiveOptions::paced: waits until the frame with this timestamp is due (a camera's pace: the
   * first frame delivered sets the clock; a consumer slower than that is never waited for). */
  void pace(double timestamp);
  /** Records a delivered frame (or its raw observation); false (stream ended) on a recording error. */
  bool record(const TFrame& f, mrpt::obs::CObservation& obs);
};
}  // namespace immslam::io
