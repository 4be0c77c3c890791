/* imm-monoslam — conversion of a dataset folder into an MRPT rawlog (program dataset2rawlog). */
#pragma once

#include <iosfwd>
#include <string>
#include <vector>

namespace immslam::io
{
/** Layout of a written rawlog. */
enum class ERawlogLayout
{
  Observations,  ///< plain sequence of observations (as `rawlog-grabber` writes)
  SensoryFrames  ///< pairs (empty CActionCollection, CSensoryFrame with one observation), as `kf-slam` reads
};

/** Options of convertDatasetToRawlog(). */
struct TDataset2RawlogOptions
{
  /** true: the pixels are stored in the rawlog (lossless: grey images ZIP-compressed by MRPT, colour
   * images raw, 16-bit images as their 8-bit conversion); false: images are referenced externally. */
  bool embedImages = false;
  /** Layout of the written file. */
  ERawlogLayout layout = ERawlogLayout::Observations;
};

/** What convertDatasetToRawlog() wrote. */
struct TDataset2RawlogResult
{
  std::size_t nImages = 0;       ///< CObservationImage written
  std::size_t nGroundTruth = 0;  ///< CObservationRobotPose (label GT) written
  std::size_t nSkipped = 0;      ///< rgb.txt entries not converted (malformed line, missing/unreadable image)
  bool calibrationStored = false;  ///< cameraParams holds the calib.txt model
  /** Human-readable warnings: skipped entries, a calibration TCamera cannot represent (the
   * calib.txt line to pass with --calib is included), no calib.txt. */
  std::vector<std::string> warnings;
};

/** Converts a dataset folder (../shared/data/README.md format) into a gzip-compressed MRPT rawlog
 * (`mrpt::io::CFileGZOutputStream`).
 *
 * Written objects, interleaved by timestamp (ground truth first at equal times):
 * - one `CObservationImage` per rgb.txt entry: sensor label `CAMERA`, timestamp
 *   `mrpt::Clock::fromDouble(rgb.txt time)`, `cameraParams` = camera::toTCamera(calib.txt model)
 *   when TCamera can represent it (pinhole, opencv), else left default (all zero: readers must take
 *   the calibration from elsewhere, e.g. `--calib`; a warning with the calib.txt line is returned);
 * - when groundtruth.txt exists, one `CObservationRobotPose` per pose: sensor label `GT`,
 *   `pose.mean` = T_W_C (camera optical frame x right, y down, z forward: NOT MRPT's x-forward body
 *   convention), `pose.cov` = diag(1e-6) (a nominal value: the files carry no uncertainty). The mean
 *   is serialized by MRPT as yaw/pitch/roll; they are computed here from the quaternion (MRPT's own
 *   matrix -> angles conversion loses up to 5e-3 rad within ~0.3 deg of pitch = +-90 deg).
 *
 * External images (embedImages = false): `CImage::setExternalStorage(name)` with `name` the image
 * path relative to the directory of `outRawlog` (e.g. `../data/visp_rbt/rgb/000001.png`), or the
 * absolute path when no relative path exists. CRawlogSource resolves such names; MRPT tools need
 * `CImage::setImagesPathBase(<rawlog dir>)`. Missing image files are skipped (warning); undecodable
 * ones are only detected when read. Embedded images are decoded and stored.
 *
 * \throws std::runtime_error naming the file: unreadable folder/rgb.txt/calib.txt/groundtruth.txt,
 * output not writable. */
TDataset2RawlogResult convertDatasetToRawlog(
    const std::string& folder, const std::string& outRawlog, const TDataset2RawlogOptions& opts = {});

/** The command line `dataset2rawlog FOLDER OUT.rawlog [--embed] [--layout obs|sf] [--help]`
 * (a library function so tests can run it).
 * \param args the arguments after the program name.
 * \return exit status: 0 success, 1 failure (message names the file), 2 bad usage. */
int dataset2rawlogCli(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);
}  // namespace immslam::io
