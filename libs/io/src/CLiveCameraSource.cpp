/* imm-monoslam — live image source over mrpt::hwdrivers::CCameraSensor. The grabber section is read
 * and checked in live_section.cpp, the grab loop and the frames are in live_grabber.cpp. */
#include <immslam/io/CLiveCameraSource.h>

#include "image_convert.h"
#include "live_grabber.h"

#include <sstream>
#include <stdexcept>

namespace immslam::io
{
namespace
{
std::string cameraText(const camera::CCameraModel::Ptr& c)
{
  if (!c) return "none";
  return c->modelName() + " " + std::to_string(c->width()) + "x" + std::to_string(c->height());
}
}  // namespace

std::pair<std::string, std::string> splitLiveSpec(const std::string& spec)
{
  const auto pos = spec.rfind(':');
  if (pos != std::string::npos && pos + 1 < spec.size() && spec.find('/', pos) == std::string::npos)
    return {spec.substr(0, pos), spec.substr(pos + 1)};
  if (pos != std::string::npos && pos + 1 == spec.size()) return {spec.substr(0, pos), "CAMERA"};
  return {spec, "CAMERA"};
}

CLiveCameraSource::CLiveCameraSource(const std::string& iniPath, const std::string& section,
                                     TLiveOptions options)
    : m_impl(std::make_unique<Impl>())
{
  Impl& m = *m_impl;
  m.iniPath = iniPath;
  m.section = section;
  m.opts = std::move(options);
  m.where = iniPath + " [" + section + "]";
  if (!(m.opts.frameRateHz > 0))
    throw std::runtime_error(m.err("frame rate must be > 0 (got " + std::to_string(m.opts.frameRateHz) + ")"));

  // The section, checked, and adjusted for MRPT (resolved paths, no grey conversion, no preview).
  mrpt::config::CConfigFileMemory cfg;
  detail::loadLiveSection(m, cfg, m.opts.strictKeys);
  m.imgDirNext = m.startIndex;
  m.resolveModes();
  m.open(cfg);
  // First frame: calibration and an early failure for sources that give nothing.
  m.readFirstFrame(m_stopRequested);
}

CLiveCameraSource::~CLiveCameraSource() = default;

ENextStatus CLiveCameraSource::next(TFrame& frame, std::string& why)
{
  Impl& m = *m_impl;
  why.clear();
  try
  {
    if (m_stopRequested.load() && !m.ended) m.end("stopped by user");
    if (m.ended)
    {
      why = m.endWhy;
      return ENextStatus::End;
    }
    if (m.pending.empty() && !m.grab(m_stopRequested))
    {
      why = m.endWhy;
      return ENextStatus::End;
    }
    const Impl::TPending p = m.pending.front();
    m.pending.pop_front();
    const ENextStatus st = m.frameOf(p, frame, why);
    if (st == ENextStatus::Frame && m.opts.paced) m.pace(frame.timestamp);
    return st;
  }
  catch (const std::exception& e)
  {
    m.end("live capture error: " + detail::mrptMessage(e.what()));
    why = m.endWhy;
    return ENextStatus::End;
  }
}

camera::CCameraModel::Ptr CLiveCameraSource::calibration() const { return m_impl->calib; }

std::string CLiveCameraSource::describe() const
{
  const Impl& m = *m_impl;
  std::ostringstream s;
  s << "live camera " << m.where << ": grabber " << m.grabber;
  if (!m.url.empty()) s << " " << m.url;
  if (m.grabber == "image_dir")
    s << " (" << m.leftPattern->before << m.leftPattern->spec << m.leftPattern->after << ", "
      << m.startIndex << ".." << m.endIndex << ")";
  if (m.mode == ETimestampMode::FrameIndex)
    s << ", frame-index time at " << m.opts.frameRateHz << " Hz";
  else
    s << ", source timestamps";
  s << ", calibration " << cameraText(m.calib);
  if (m.calib) s << (m.calib == m.opts.camera ? " (given)" : " (from the observations)");
  return s.str();
}

std::size_t CLiveCameraSource::sizeHint() const
{
  const Impl& m = *m_impl;
  return m.grabber == "image_dir" ? std::size_t(m.endIndex - m.startIndex + 1) : 0;
}

void CLiveCameraSource::setRecorder(std::shared_ptr<CRawlogRecorder> recorder, ERecordMode mode)
{
  m_impl->recorder = std::move(recorder);
  m_impl->recordMode = mode;
}

const std::string& CLiveCameraSource::grabberType() const { return m_impl->grabber; }
ETimestampMode CLiveCameraSource::timestampMode() const { return m_impl->mode; }
const std::vector<std::string>& CLiveCameraSource::warnings() const { return m_impl->warnings; }
std::size_t CLiveCameraSource::framesDelivered() const { return m_impl->delivered; }
}  // namespace immslam::io
