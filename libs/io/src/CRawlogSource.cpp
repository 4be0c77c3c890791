/* imm-monoslam — rawlog image source (both layouts, damage-tolerant). */
#include <immslam/camera/mrpt_camera.h>
#include <immslam/io/CRawlogSource.h>

#include "image_convert.h"
#include "observation_image.h"
#include "rawlog_stream.h"

#include <mrpt/core/Clock.h>
#include <mrpt/img/CImage.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CObservationImage.h>
#include <mrpt/obs/CObservationRobotPose.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose3D.h>

#include <Eigen/Geometry>

#include <deque>
#include <filesystem>
#include <map>
#include <sstream>

namespace fs = std::filesystem;

namespace immslam::io
{
namespace
{
/** One observation (or unknown object) of the stream, with where it came from. */
struct TItem
{
  mrpt::obs::CObservation::Ptr obs;  ///< null for a non-observation object
  std::string className;             ///< class of the object
  std::size_t entry = 0;             ///< 0-based top-level object index
  int sub = -1;                      ///< index inside a sensory frame, -1 at top level
};

/** Splits a top-level object into stream items (actions carry nothing for us). */
void expandEntry(const mrpt::serialization::CSerializable::Ptr& obj, std::size_t entry,
                 std::deque<TItem>& out, bool& sawSensoryFrame)
{
  using namespace mrpt::obs;
  if (auto sf = std::dynamic_pointer_cast<CSensoryFrame>(obj))
  {
    sawSensoryFrame = true;
    int i = 0;
    for (const auto& o : *sf)
    {
      if (o) out.push_back({o, o->GetRuntimeClass()->className, entry, i});
      ++i;
    }
  }
  else if (auto o = std::dynamic_pointer_cast<CObservation>(obj))
    out.push_back({o, o->GetRuntimeClass()->className, entry, -1});
  else if (std::dynamic_pointer_cast<CActionCollection>(obj))
    sawSensoryFrame = true;
  else
    out.push_back({nullptr, obj->GetRuntimeClass()->className, entry, -1});
}

bool isGroundTruth(const mrpt::obs::CObservation& o)
{
  return o.sensorLabel == "GT" && dynamic_cast<const mrpt::obs::CObservationRobotPose*>(&o);
}

core::TStampedPose toStampedPose(const mrpt::obs::CObservationRobotPose& o)
{
  // The quaternion comes from the rotation matrix, not from CPose3D::getAsQuaternion(): that one
  // goes through yaw/pitch/roll, which MRPT snaps to pitch = +-90 deg near gimbal lock (errors of
  // 1e-3 seen on monoslammot_synth19), while the matrix survives serialization exactly.
  const mrpt::poses::CPose3D& m = o.pose.mean;
  const auto R = m.getRotationMatrix();
  Mat3 R_W_C;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) R_W_C(r, c) = R(r, c);
  Eigen::Quaterniond q(R_W_C);
  q.normalize();
  if (q.w() < 0) q.coeffs() *= -1.0;  // canonical sign: qw >= 0
  core::TStampedPose p;
  p.timestamp = mrpt::Clock::toDouble(o.timestamp);
  p.p_W_C = Vec3(m.x(), m.y(), m.z());
  p.q_W_C = Vec4(q.w(), q.x(), q.y(), q.z());  // [qw qx qy qz], as mrpt::math::CQuaternion (r,x,y,z)
  return p;
}

std::string originOf(const TItem& it)
{
  std::string s = "rawlog entry " + std::to_string(it.entry);
  if (it.sub >= 0) s += ", observation " + std::to_string(it.sub) + " of its sensory frame";
  return s;
}
}  // namespace

struct CRawlogSource::Impl
{
  std::string path;
  std::string rawlogDir;
  std::string imagesDir;  ///< "<dir>/<stem>_Images" if it exists, else rawlogDir
  detail::TGzipInfo gzInfo;

  // First-pass results.
  std::size_t firstPassEntries = 0;
  std::size_t items = 0;
  std::map<std::string, std::size_t> imageLabels;  ///< items with a camera image, by sensor label
  std::vector<std::string> labelOrder;             ///< sensor labels of images, first seen first
  std::string wantedLabel;                         ///< the constructor's choice (empty: the first)
  std::string label;                               ///< the sensor whose images are the frames
  std::map<std::string, std::size_t> otherClasses;  ///< other items by class (ground truth excluded)
  bool sensoryFrames = false;
  std::string damage;  ///< empty: clean end
  camera::CCameraModel::Ptr calib;
  core::TTrajectory gt;
  std::vector<std::string> warnings;

  // Streaming state (second pass).
  std::unique_ptr<detail::CRawlogReader> reader;
  std::deque<TItem> pending;
  std::size_t nextIndex = 0;
  bool ended = false;
  std::string endWhy;

  // Calibration cache.
  std::optional<mrpt::img::TCamera> lastTCam;
  camera::CCameraModel::Ptr lastCam;

  camera::CCameraModel::Ptr cameraOf(const mrpt::img::TCamera& c, std::string* err)
  {
    if (lastTCam && *lastTCam == c) return lastCam;
    lastTCam = c;
    lastCam.reset();
    if (!detail::isEmptyCamera(c))
    {
      try
      {
        lastCam = camera::fromTCamera(c);
      }
      catch (const std::exception& e)
      {
        if (err) *err = e.what();
      }
    }
    return lastCam;
  }

  std::string resolveExternal(const std::string& name, std::string& tried) const
  {
    const fs::path p(name);
    if (p.is_absolute())
    {
      tried = name;
      return name;
    }
    std::error_code ec;
    const std::string a = (fs::path(imagesDir) / p).string();
    const std::string b = (fs::path(rawlogDir) / p).string();
    if (fs::is_regular_file(a, ec)) return a;
    if (fs::is_regular_file(b, ec)) return b;
    tried = (a == b) ? a : a + " nor " + b;
    return {};
  }

  void firstPass()
  {
    detail::CRawlogReader r(path, gzInfo);
    std::deque<TItem> its;
    std::string camErr;
    for (;;)
    {
      mrpt::serialization::CSerializable::Ptr obj;
      std::string why;
      const auto res = r.read(obj, why);
      if (res == detail::CRawlogReader::EResult::End) break;
      if (res == detail::CRawlogReader::EResult::Damage)
      {
        if (r.entries() == 0 && items == 0)
          throw std::runtime_error("cannot read rawlog " + path + " (not an MRPT rawlog?): " + why);
        damage = damageReport(r.entries(), why);
        break;
      }
      its.clear();
      expandEntry(obj, r.entries() - 1, its, sensoryFrames);
      for (const TItem& it : its)
      {
        if (it.obs && isGroundTruth(*it.obs))
        {
          gt.push_back(toStampedPose(dynamic_cast<const mrpt::obs::CObservationRobotPose&>(*it.obs)));
          continue;
        }
        ++items;
        const detail::TImageView v = it.obs ? detail::imageOf(*it.obs) : detail::TImageView{};
        if (!v.image)
        {
          ++otherClasses[it.className];
          continue;
        }
        if (imageLabels[it.obs->sensorLabel]++ == 0) labelOrder.push_back(it.obs->sensorLabel);
        // The calibration of the first image of the sensor used (the first sensor unless one is asked for).
        if (calib || it.obs->sensorLabel != (wantedLabel.empty() ? labelOrder.front() : wantedLabel)) continue;
        camErr.clear();
        calib = cameraOf(*v.camera, &camErr);
        if (!camErr.empty()) warnings.push_back(originOf(it) + ": camera parameters not usable: " + camErr);
      }
    }
    firstPassEntries = r.entries();
  }

  /** The damage report of next()/damage(): names the file and the last complete entry. */
  std::string damageReport(std::size_t entries, const std::string& why) const
  {
    return "rawlog truncated/corrupt after entry " + std::to_string(entries) + " of " + path + ": " + why;
  }

  /** The labels of the image sensors, "'A' (n images), 'B' (m images)". */
  std::string labelList() const
  {
    std::string list;
    for (const auto& l : labelOrder)
      list += (list.empty() ? "'" : ", '") + l + "' (" + std::to_string(imageLabels.at(l)) + " images)";
    return list;
  }

  /** Picks the sensor whose images are the frames: the asked one (an error naming the sensors held if
   * the file has none of its images) or the first one seen (a warning if there are others). */
  void chooseLabel()
  {
    if (!wantedLabel.empty())
    {
      if (!imageLabels.count(wantedLabel))
        throw std::runtime_error("rawlog " + path + " holds no image of sensor '" + wantedLabel +
                                 "' ([input] rawlog_sensor_label); its image sensors: " + labelList());
      label = wantedLabel;
    }
    else
      label = labelOrder.front();
    if (labelOrder.size() > 1)
      warnings.push_back("rawlog holds the images of " + std::to_string(labelOrder.size()) + " sensors, " + labelList() +
                         ": using '" + label + "'" +
                         (wantedLabel.empty() ? " (the first; choose with [input] rawlog_sensor_label)" : "") +
                         ", the others' images are skipped");
  }

  /** An input without a single image is an error (not an empty run): names the file and what it holds. */
  void requireImages() const
  {
    if (!imageLabels.empty()) return;
    std::string what;
    if (firstPassEntries == 0)
      what = "is empty (no object)";
    else
    {
      what = "holds no image observation (CObservationImage, CObservationStereoImages, or CObservation3DRangeScan "
             "with an intensity image); it holds";
      std::string list;
      for (const auto& [cls, n] : otherClasses) list += (list.empty() ? " " : ", ") + std::to_string(n) + " " + cls;
      if (!gt.empty()) list += (list.empty() ? " " : ", ") + std::to_string(gt.size()) + " ground-truth poses";
      what += list.empty() ? " nothing usable" : list;
    }
    if (!damage.empty()) what += " (then: " + damage + ")";
    throw std::runtime_error("rawlog " + path + " " + what + ": nothing to process");
  }

  /** The next item that is not ground truth (read from the file as needed); false at the end
   * (`why`: the damage, or "" at the normal end). */
  bool nextItem(TItem& it, std::string& why);
};

bool CRawlogSource::Impl::nextItem(TItem& it, std::string& why)
{
  for (;;)
  {
    while (pending.empty())
    {
      if (ended)
      {
        why = endWhy;
        return false;
      }
      if (!damage.empty() && reader->entries() >= firstPassEntries)
      {
        // Stop where the first pass found the damage (the same place, whatever the reader does).
        ended = true;
        endWhy = damage;
        reader.reset();
        continue;
      }
      mrpt::serialization::CSerializable::Ptr obj;
      std::string err;
      const auto res = reader->read(obj, err);
      if (res == detail::CRawlogReader::EResult::Object)
      {
        bool sf = false;
        expandEntry(obj, reader->entries() - 1, pending, sf);
        continue;
      }
      ended = true;
      if (res == detail::CRawlogReader::EResult::Damage)
        endWhy = damageReport(reader->entries(), err);
      reader.reset();  // releases the file
    }
    it = std::move(pending.front());
    pending.pop_front();
    if (!(it.obs && isGroundTruth(*it.obs))) return true;  // ground truth: consumed silently
  }
}

CRawlogSource::CRawlogSource(const std::string& path, const std::string& sensorLabel) : m_impl(std::make_unique<Impl>())
{
  Impl& m = *m_impl;
  m.path = path;
  m.wantedLabel = sensorLabel;
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw std::runtime_error("rawlog file not found: " + path);
  m.gzInfo = detail::inspectGzip(path);
  const fs::path p(path);
  m.rawlogDir = p.has_parent_path() ? p.parent_path().string() : std::string(".");
  m.imagesDir = m.rawlogDir;
  const std::string stem = p.stem().string();
  for (const std::string& name : {stem + "_Images", stem + "_images", stem + "_IMAGES", std::string("Images")})
  {
    const fs::path d = fs::path(m.rawlogDir) / name;
    if (fs::is_directory(d, ec))
    {
      m.imagesDir = d.string();
      break;
    }
  }
  m.firstPass();
  m.requireImages();
  m.chooseLabel();
  // For MRPT code that loads the same observations' external images (process-wide setting).
  mrpt::img::CImage::setImagesPathBase(m.imagesDir);
  m.lastTCam.reset();
  m.reader = std::make_unique<detail::CRawlogReader>(path, m.gzInfo);
}

CRawlogSource::~CRawlogSource() = default;

bool CRawlogSource::endedOnDamage() const { return m_impl->ended && !m_impl->endWhy.empty(); }

ENextStatus CRawlogSource::next(TFrame& frame, std::string& why)
{
  Impl& m = *m_impl;
  why.clear();
  try
  {
    TItem it;
    if (!m.nextItem(it, why)) return ENextStatus::End;

    const std::size_t index = m.nextIndex++;
    const std::string origin = originOf(it);
    const detail::TImageView v = it.obs ? detail::imageOf(*it.obs) : detail::TImageView{};
    if (!v.image)
    {
      why = "observation of class " + it.className +
            (it.obs ? " (label '" + it.obs->sensorLabel + "')" : std::string()) + " skipped (" +
            origin + ")";
      return ENextStatus::Skipped;
    }
    if (it.obs->sensorLabel != m.label)
    {
      why = "image of sensor '" + it.obs->sensorLabel + "' skipped, the frames come from sensor '" + m.label + "' (" +
            origin + ")";
      return ENextStatus::Skipped;
    }
    if (it.obs->timestamp == INVALID_TIMESTAMP)
    {
      why = it.className + " without timestamp skipped (" + origin + ")";
      return ENextStatus::Skipped;
    }
    TFrame f;
    f.timestamp = mrpt::Clock::toDouble(it.obs->timestamp);
    f.index = index;
    f.origin = origin;
    std::string sub;
    // External image <=> a file name. (Not isExternallyStored(): MRPT deserializes that flag from a
    // raw byte into a bool, and a corrupt byte such as 129 makes reading it undefined behaviour;
    // found by fuzzing, tests/fuzz/regressions/rawlog/image_external_flag_129.rawlog.)
    if (const std::string name = v.image->getExternalStorageFile(); !name.empty())
    {
      std::string tried;
      const std::string file = m.resolveExternal(name, tried);
      if (file.empty())
      {
        why = "external image not found: " + tried + " (" + origin + ")";
        return ENextStatus::Skipped;
      }
      f.origin = origin + " (" + file + ")";
      if (!detail::loadFrameImages(file, f, sub))
      {
        why = sub + " (" + origin + ")";
        return ENextStatus::Skipped;
      }
    }
    else if (!detail::setFrameImages(v.image->asCvMatRef(), f, sub))
    {
      why = "embedded image: " + sub + " (" + origin + ")";
      return ENextStatus::Skipped;
    }
    f.camera = m.cameraOf(*v.camera, nullptr);
    frame = std::move(f);
    return ENextStatus::Frame;
  }
  catch (const std::exception& e)
  {
    // Anything unexpected (e.g. an image MRPT cannot expose) skips that item, never escapes.
    why = "error reading " + m.path + ": " + detail::mrptMessage(e.what());
    return ENextStatus::Skipped;
  }
}

camera::CCameraModel::Ptr CRawlogSource::calibration() const { return m_impl->calib; }

std::optional<core::TTrajectory> CRawlogSource::groundTruth() const
{
  if (m_impl->gt.empty()) return std::nullopt;
  return m_impl->gt;
}

std::string CRawlogSource::describe() const
{
  const Impl& m = *m_impl;
  std::ostringstream s;
  s << "rawlog " << m.path << " (" << m.items << " observations in " << m.firstPassEntries
    << " entries, " << (m.sensoryFrames ? "action/sensory-frame pairs" : "plain observations");
  s << ", " << (m.calib ? m.calib->modelName() + " camera" : std::string("no calibration"));
  if (!m.gt.empty()) s << ", ground truth " << m.gt.size() << " poses";
  if (!m.damage.empty()) s << "; " << m.damage;
  s << ")";
  return s.str();
}

std::size_t CRawlogSource::sizeHint() const { return m_impl->items; }
std::size_t CRawlogSource::entryCount() const { return m_impl->firstPassEntries; }
const std::string& CRawlogSource::damage() const { return m_impl->damage; }
bool CRawlogSource::hasSensoryFrames() const { return m_impl->sensoryFrames; }
const std::vector<std::string>& CRawlogSource::warnings() const { return m_impl->warnings; }
const std::string& CRawlogSource::imagesDirectory() const { return m_impl->imagesDir; }
}  // namespace immslam::io
