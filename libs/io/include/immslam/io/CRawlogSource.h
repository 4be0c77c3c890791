/* imm-monoslam — image source streaming an MRPT .rawlog file (either layout). */
#pragma once

#include <immslam/io/CImageSource.h>

#include <memory>
#include <string>
#include <vector>

namespace immslam::io
{
/** Streams the images of an MRPT rawlog (gzip-compressed or plain), in either layout: plain
 * observations (what `rawlog-grabber` writes) or action / sensory-frame pairs (what `kf-slam` reads;
 * the observations of each sensory frame are visited in order, actions are ignored).
 *
 * What becomes what:
 * - every observation carrying a camera image of the chosen sensor is one frame: a
 *   `mrpt::obs::CObservationImage` (`image`, `cameraParams`), a `CObservationStereoImages` (the left
 *   image and `leftCamera`) or a `CObservation3DRangeScan` with an intensity image (`intensityImage`,
 *   `cameraParamsIntensity`). Timestamp = `mrpt::Clock::toDouble`, image (embedded or external)
 *   converted as in CDatasetFolderSource (grey + kept colour, 16 -> 8 bits), TFrame::camera from the
 *   TCamera (camera::fromTCamera) unless that TCamera is empty (zero focal length or size: e.g. a
 *   davison camera that TCamera cannot represent);
 * - the chosen sensor is the `sensorLabel` given to the constructor or else the first one whose
 *   image the file holds; the images of other sensors (a second camera, the other half of a stereo
 *   rig logged as two CObservationImage) give ENextStatus::Skipped naming their sensor, and
 *   warnings() says which sensors the file holds;
 * - `CObservationRobotPose` with sensor label `GT` is ground truth T_W_C (optical frame, x right,
 *   y down, z forward: the pose mean, quaternion from `CPose3D::getAsQuaternion`); it is consumed
 *   silently (groundTruth() has all of them);
 * - any other observation (or unknown top-level object) gives ENextStatus::Skipped
 *   ("observation of class X skipped").
 *
 * Construction makes a quick first pass over the file (external images are not loaded; embedded
 * images are decompressed) to collect the ground truth, count the items (sizeHint(): the number
 * of next() results before End) and take the first usable calibration. A truncated or corrupt file
 * ends the stream cleanly: next() returns End with why = "rawlog truncated/corrupt after entry N of
 * <path>: <details>" at the same place in both passes (N = number of complete top-level objects).
 * A gzip stream cut exactly between two objects is recognised by its missing trailer.
 *
 * External images: a relative file name is resolved against, in order, the MRPT convention
 * `<rawlog dir>/<rawlog name without extension>_Images` (also `_images`, `_IMAGES`, then
 * `<rawlog dir>/Images`; the first that exists) and the rawlog's own folder (what
 * convertDatasetToRawlog() writes); absolute names are used as they are. Images are
 * decoded with cv::imread (not through MRPT's process-wide image path), but the constructor also
 * calls `mrpt::img::CImage::setImagesPathBase` with the resolved folder so that MRPT code handling
 * the same observations finds the images (a process-wide MRPT setting: the last opened rawlog wins).
 * An external image that cannot be found or decoded gives Skipped naming the image path.
 *
 * next() never throws. Not thread-safe. */
class CRawlogSource : public CImageSource
{
 public:
  /** Opens `path` and makes the first pass. `sensorLabel`: the sensor whose images are the frames
   * (empty: the first one in the file).
   * \throws std::runtime_error naming the path if the file cannot be opened, its very first
   * object cannot be read (not a rawlog), it holds no camera image at all (an empty file, or only
   * other observations / ground truth: the message lists what it holds), or none of `sensorLabel`
   * (the message lists the image sensors it holds). */
  explicit CRawlogSource(const std::string& path, const std::string& sensorLabel = "");
  ~CRawlogSource() override;
  CRawlogSource(const CRawlogSource&) = delete;
  CRawlogSource& operator=(const CRawlogSource&) = delete;

  ENextStatus next(TFrame& frame, std::string& why) override;
  camera::CCameraModel::Ptr calibration() const override;
  std::optional<core::TTrajectory> groundTruth() const override;
  std::string describe() const override;
  std::size_t sizeHint() const override;
  bool endedOnDamage() const override;

  /** Number of top-level objects read without error by the first pass. */
  std::size_t entryCount() const;
  /** Empty if the first pass reached a clean end of file, else the damage report that next() will
   * return with End ("rawlog truncated/corrupt after entry N: ..."). */
  const std::string& damage() const;
  /** True if the file holds action / sensory-frame pairs (false: plain observations). */
  bool hasSensoryFrames() const;
  /** Non-fatal problems of the first pass (e.g. a cameraParams that could not be converted). */
  const std::vector<std::string>& warnings() const;
  /** The folder relative external image names are resolved against first (see class docs). */
  const std::string& imagesDirectory() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};
}  // namespace immslam::io
