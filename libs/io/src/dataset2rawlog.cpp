/* imm-monoslam — dataset folder -> MRPT rawlog conversion. */
#include <immslam/camera/mrpt_camera.h>
#include <immslam/io/CDatasetFolderSource.h>
#include <immslam/io/dataset2rawlog.h>

#include "image_convert.h"

#include <mrpt/core/Clock.h>
#include <mrpt/img/CImage.h>
#include <mrpt/img/TCamera.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/math/CMatrixFixed.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CObservationImage.h>
#include <mrpt/obs/CObservationRobotPose.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose3D.h>
#include <mrpt/poses/CPose3DPDFGaussian.h>
#include <mrpt/serialization/CArchive.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>

namespace fs = std::filesystem;

namespace immslam::io
{
namespace
{
/** Sets CImage::DISABLE_JPEG_COMPRESSION (an MRPT process-wide flag) for its lifetime so that
 * embedded colour images are stored losslessly, then restores it. */
class CLosslessImagesGuard
{
 public:
  CLosslessImagesGuard() : m_old(mrpt::img::CImage::DISABLE_JPEG_COMPRESSION())
  {
    mrpt::img::CImage::DISABLE_JPEG_COMPRESSION(true);
  }
  ~CLosslessImagesGuard() { mrpt::img::CImage::DISABLE_JPEG_COMPRESSION(m_old); }
  CLosslessImagesGuard(const CLosslessImagesGuard&) = delete;
  CLosslessImagesGuard& operator=(const CLosslessImagesGuard&) = delete;

 private:
  bool m_old;
};

/** Something to write, in time order. */
struct TEvent
{
  double t = 0;
  int kind = 0;  ///< 0: ground truth pose, 1: image (ground truth first at equal times)
  std::size_t idx = 0;
};

/** The name under which an external image is stored: relative to the rawlog's directory when
 * possible, else absolute (both through canonical paths, so symbolic links resolve alike). */
std::string externalName(const std::string& image, const fs::path& rawlogDirCanon)
{
  std::error_code ec;
  fs::path abs = fs::weakly_canonical(fs::absolute(image), ec);
  if (ec) abs = fs::absolute(image).lexically_normal();
  const fs::path rel = abs.lexically_relative(rawlogDirCanon);
  return rel.empty() ? abs.string() : rel.generic_string();
}

/** The CPose3D of T_W_C built from yaw/pitch/roll computed here from the quaternion.
 * CPose3DPDFGaussian serializes its mean as (x y z yaw pitch roll), and MRPT's own rotation-matrix
 * -> yaw/pitch/roll conversion snaps pitch to +-90 deg when cos(pitch) is below ~5e-3 (rotation
 * errors up to 5e-3 on monoslammot_synth19): atan2 on the matrix of the quaternion is exact to
 * ~1e-15 there, and at an exact gimbal lock (roll := 0) the rotation is still represented exactly. */
mrpt::poses::CPose3D toPose3D(const core::TStampedPose& p)
{
  const Eigen::Quaterniond q(p.q_W_C[0], p.q_W_C[1], p.q_W_C[2], p.q_W_C[3]);
  const Mat3 R = q.normalized().toRotationMatrix();  // R = Rz(yaw) Ry(pitch) Rx(roll)
  const double cp = std::hypot(R(0, 0), R(1, 0));
  const double pitch = std::atan2(-R(2, 0), cp);
  double yaw = 0, roll = 0;
  if (cp > 1e-12)
  {
    yaw = std::atan2(R(1, 0), R(0, 0));
    roll = std::atan2(R(2, 1), R(2, 2));
  }
  else
    yaw = std::atan2(-R(0, 1), R(1, 1));
  return mrpt::poses::CPose3D(p.p_W_C.x(), p.p_W_C.y(), p.p_W_C.z(), yaw, pitch, roll);
}

mrpt::obs::CObservationRobotPose::Ptr makeGroundTruth(const core::TStampedPose& p)
{
  auto o = mrpt::obs::CObservationRobotPose::Create();
  o->sensorLabel = "GT";
  o->timestamp = mrpt::Clock::fromDouble(p.timestamp);
  o->pose.mean = toPose3D(p);
  o->pose.cov.setZero();
  for (int i = 0; i < 6; ++i) o->pose.cov(i, i) = 1e-6;
  return o;
}
/** The calibration stored with every image: the folder's calib.txt as MRPT's TCamera, or all
 * zero ("no calibration" for CRawlogSource) with a warning in `res`. */
mrpt::img::TCamera storedCalibration(const CDatasetFolderSource& src, const std::string& folder,
                                     TDataset2RawlogResult& res)
{
  mrpt::img::TCamera tcam;
  const std::string calibFile = (fs::path(folder) / "calib.txt").string();
  if (const auto cam = src.calibration())
  {
    if (const auto tc = camera::toTCamera(*cam))
    {
      tcam = *tc;
      res.calibrationStored = true;
    }
    else
      res.warnings.push_back(
          "the " + cam->modelName() + " camera model of " + calibFile +
          " cannot be represented by MRPT's TCamera: cameraParams left empty; run with "
          "--calib FILE, FILE holding the line: " + cam->toCalibLine());
  }
  else
    res.warnings.push_back("no " + calibFile + ": cameraParams left empty (run with --calib FILE)");
  return tcam;
}

/** The folder's images (those rgb.txt lists without error; the others counted as skipped in `res`)
 * and ground-truth poses in time order, ground truth first at equal times. */
std::vector<TEvent> timeOrderedEvents(const std::vector<TDatasetEntry>& entries, const core::TTrajectory& gt,
                                      TDataset2RawlogResult& res)
{
  std::vector<TEvent> events;
  events.reserve(entries.size() + gt.size());
  for (std::size_t i = 0; i < entries.size(); ++i)
  {
    if (!entries[i].error.empty())
    {
      res.warnings.push_back("skipped: " + entries[i].error);
      ++res.nSkipped;
      continue;
    }
    events.push_back({entries[i].timestamp, 1, i});
  }
  for (std::size_t i = 0; i < gt.size(); ++i) events.push_back({gt[i].timestamp, 0, i});
  std::stable_sort(events.begin(), events.end(), [](const TEvent& a, const TEvent& b) {
    return a.t < b.t || (a.t == b.t && a.kind < b.kind);
  });
  return events;
}
/** The observation of image entry `e` (its image embedded, or referenced by its file name relative
 * to `outDir`); null when the image is unreadable or missing (warning counted in `res`). */
mrpt::obs::CObservationImage::Ptr imageObservation(const CDatasetFolderSource& src, const TDatasetEntry& e,
                                                   const mrpt::img::TCamera& tcam, bool embed, const fs::path& outDir,
                                                   TDataset2RawlogResult& res)
{
  std::error_code ec;
  const std::string file = src.imagePath(e);
  auto obs = mrpt::obs::CObservationImage::Create();
  obs->sensorLabel = "CAMERA";
  obs->timestamp = mrpt::Clock::fromDouble(e.timestamp);
  obs->cameraParams = tcam;
  if (embed)
  {
    TFrame fr;
    std::string why;
    if (!detail::loadFrameImages(file, fr, why))
    {
      res.warnings.push_back("skipped: " + why + " (rgb.txt:" + std::to_string(e.line) + ")");
      ++res.nSkipped;
      return nullptr;
    }
    obs->image = mrpt::img::CImage(fr.colour.empty() ? fr.grey : fr.colour, mrpt::img::SHALLOW_COPY);
  }
  else
  {
    if (!fs::is_regular_file(file, ec))
    {
      res.warnings.push_back(
          "skipped: missing image file " + file + " (rgb.txt:" + std::to_string(e.line) + ")");
      ++res.nSkipped;
      return nullptr;
    }
    obs->image.setExternalStorage(externalName(file, outDir));
  }
  return obs;
}
}  // namespace

TDataset2RawlogResult convertDatasetToRawlog(
    const std::string& folder, const std::string& outRawlog, const TDataset2RawlogOptions& opts)
{
  TDataset2RawlogResult res;
  CDatasetFolderSource src(folder);  // throws naming rgb.txt / calib.txt / groundtruth.txt

  const mrpt::img::TCamera tcam = storedCalibration(src, folder, res);

  const auto& entries = src.entries();
  const core::TTrajectory gt = src.groundTruth().value_or(core::TTrajectory{});
  const std::vector<TEvent> events = timeOrderedEvents(entries, gt, res);

  std::error_code ec;
  fs::path outDir = fs::absolute(outRawlog).parent_path();
  const fs::path outDirCanon = fs::weakly_canonical(outDir, ec);
  if (!ec) outDir = outDirCanon;

  mrpt::io::CFileGZOutputStream f;
  std::string openErr;
  if (!f.open(outRawlog, 1, openErr))
    throw std::runtime_error("cannot write " + outRawlog + (openErr.empty() ? "" : ": " + openErr));
  auto arch = mrpt::serialization::archiveFrom(f);
  const CLosslessImagesGuard lossless;

  auto write = [&](const mrpt::obs::CObservation::Ptr& obs) {
    if (opts.layout == ERawlogLayout::SensoryFrames)
    {
      mrpt::obs::CActionCollection acts;
      mrpt::obs::CSensoryFrame sf;
      sf.insert(obs);
      arch << acts << sf;
    }
    else
      arch << *obs;
  };

  try
  {
    for (const TEvent& ev : events)
    {
      if (ev.kind == 0)
      {
        write(makeGroundTruth(gt[ev.idx]));
        ++res.nGroundTruth;
        continue;
      }
      const auto obs = imageObservation(src, entries[ev.idx], tcam, opts.embedImages, outDir, res);
      if (!obs) continue;
      write(obs);
      ++res.nImages;
    }
    f.close();
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error("error writing " + outRawlog + ": " + detail::mrptMessage(e.what()));
  }
  return res;
}
}  // namespace immslam::io
