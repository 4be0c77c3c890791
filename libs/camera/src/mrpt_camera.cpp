/* imm-monoslam — our camera models <-> MRPT's TCamera and [CAMERA_PARAMS] config sections. */
#include <immslam/camera/CDavisonCamera.h>
#include <immslam/camera/CFisheyeCamera.h>
#include <immslam/camera/COpenCVCamera.h>
#include <immslam/camera/CPinholeCamera.h>
#include <immslam/camera/mrpt_camera.h>
#include <immslam/math/text.h>

#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/img/TCamera.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <climits>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace immslam::camera
{
namespace
{
bool parseDouble(const std::string& word, double& out)
{
  const char* end = word.data() + word.size();
  const auto res = std::from_chars(word.data(), end, out);
  return res.ec == std::errc() && res.ptr == end && std::isfinite(out);
}

/** Reads the keys of one config section with errors that name the section and key. */
class CSectionReader
{
 public:
  CSectionReader(const mrpt::config::CConfigFileBase& cfg, const std::string& section)
      : m_cfg(cfg), m_section(section)
  {
  }

  std::string where() const { return "config section [" + m_section + "]"; }

  [[noreturn]] void fail(const std::string& key, const std::string& what) const
  {
    throw std::runtime_error(where() + ", key '" + key + "': " + what);
  }

  bool has(const std::string& key) const { return m_cfg.keyExists(m_section, key); }

  /** The trimmed value, or "" if the key is absent. */
  std::string str(const std::string& key) const
  {
    return has(key) ? math::trim(m_cfg.read_string(m_section, key, "", false)) : std::string();
  }

  double requiredDouble(const std::string& key) const
  {
    if (!has(key)) throw std::runtime_error(where() + ": missing key '" + key + "'");
    const std::string v = str(key);
    double out;
    if (!parseDouble(v, out)) fail(key, "'" + v + "' is not a number");
    return out;
  }

  /** A list "[a b c]" (brackets optional, commas or spaces); empty if the key is absent. */
  std::vector<double> list(const std::string& key) const
  {
    std::string v = str(key);
    std::replace_if(v.begin(), v.end(), [](char c) { return c == '[' || c == ']' || c == ','; }, ' ');
    std::istringstream ss(v);
    std::vector<double> out;
    for (std::string w; ss >> w;)
    {
      double d;
      if (!parseDouble(w, d)) fail(key, "'" + w + "' is not a number");
      out.push_back(d);
    }
    return out;
  }

 private:
  const mrpt::config::CConfigFileBase& m_cfg;
  std::string m_section;
};

/** k1 k2 p1 p2 k3 from MRPT's 4, 5 or 8 plumb_bob coefficients (k4..k6 must be zero). */
std::vector<double> plumbBob(const std::vector<double>& d, const CSectionReader& r)
{
  if (d.size() != 4 && d.size() != 5 && d.size() != 8)
    r.fail("dist", "expected 4, 5 or 8 coefficients [k1 k2 p1 p2 k3 ...], got " +
                       std::to_string(d.size()));
  if (d.size() == 8 && (d[5] != 0 || d[6] != 0 || d[7] != 0))
    r.fail("dist", "the rational coefficients k4 k5 k6 are not supported (must be 0)");
  std::vector<double> k(5, 0.0);
  std::copy(d.begin(), d.begin() + std::min<size_t>(5, d.size()), k.begin());
  return k;
}

bool allZero(const std::vector<double>& v)
{
  return std::all_of(v.begin(), v.end(), [](double x) { return x == 0; });
}

/** The model a [camera] section without `model` names by its `distortion_model` (MRPT's names):
 * none, plumb_bob (pinhole when every coefficient is 0) or kannala_brandt; absent: by `dist`. */
std::string modelFromDistortion(const CSectionReader& r, const std::vector<double>& dist)
{
  const std::string dm = math::toLower(r.str("distortion_model"));
  if (dm == "none") return "pinhole";
  if (dm == "plumb_bob")
  {
    if (!r.has("dist")) throw std::runtime_error(r.where() + ": missing key 'dist' (distortion_model = plumb_bob)");
    return allZero(plumbBob(dist, r)) ? "pinhole" : "opencv";
  }
  if (dm.empty()) return allZero(dist) ? "pinhole" : "opencv";
  if (dm == "kannala_brandt") return "fisheye";
  r.fail("distortion_model", "unknown value '" + dm + "' (expected none, plumb_bob or kannala_brandt)");
}
}  // namespace

CCameraModel::Ptr fromTCamera(const mrpt::img::TCamera& cam)
{
  if (cam.ncols == 0 || cam.nrows == 0 || cam.ncols > INT_MAX || cam.nrows > INT_MAX)
    throw std::runtime_error("TCamera: invalid image size " + std::to_string(cam.ncols) + "x" +
                             std::to_string(cam.nrows));
  if (!(cam.fx() > 0) || !(cam.fy() > 0))
    throw std::runtime_error("TCamera: focal lengths must be positive (fx = " +
                             std::to_string(cam.fx()) + ", fy = " + std::to_string(cam.fy()) + ")");
  const int w = static_cast<int>(cam.ncols), h = static_cast<int>(cam.nrows);
  switch (cam.distortion)
  {
    case mrpt::img::DistortionModel::none:
      return std::make_shared<CPinholeCamera>(w, h, cam.fx(), cam.fy(), cam.cx(), cam.cy());
    case mrpt::img::DistortionModel::plumb_bob:
      break;
    case mrpt::img::DistortionModel::kannala_brandt:
      return std::make_shared<CFisheyeCamera>(w, h, cam.fx(), cam.fy(), cam.cx(), cam.cy(), cam.k1(), cam.k2(),
                                              cam.k3(), cam.k4());
    default:
      throw std::runtime_error("TCamera: unknown distortion model " +
                               std::to_string(static_cast<int>(cam.distortion)));
  }
  if (cam.k4() != 0 || cam.k5() != 0 || cam.k6() != 0)
    throw std::runtime_error("TCamera: the rational distortion coefficients k4 k5 k6 are not supported");
  if (cam.k1() == 0 && cam.k2() == 0 && cam.p1() == 0 && cam.p2() == 0 && cam.k3() == 0)
    return std::make_shared<CPinholeCamera>(w, h, cam.fx(), cam.fy(), cam.cx(), cam.cy());
  return std::make_shared<COpenCVCamera>(w, h, cam.fx(), cam.fy(), cam.cx(), cam.cy(), cam.k1(),
      cam.k2(), cam.p1(), cam.p2(), cam.k3());
}

std::optional<mrpt::img::TCamera> toTCamera(const CCameraModel& cam)
{
  mrpt::img::TCamera t;
  t.ncols = static_cast<uint32_t>(cam.width());
  t.nrows = static_cast<uint32_t>(cam.height());
  t.setIntrinsicParamsFromValues(cam.fx(), cam.fy(), cam.cx(), cam.cy());
  if (dynamic_cast<const CPinholeCamera*>(&cam))
  {
    t.distortion = mrpt::img::DistortionModel::none;
    return t;
  }
  if (const auto* cv = dynamic_cast<const COpenCVCamera*>(&cam))
  {
    t.setDistortionPlumbBob(cv->k1(), cv->k2(), cv->p1(), cv->p2(), cv->k3());
    return t;
  }
  if (const auto* fe = dynamic_cast<const CFisheyeCamera*>(&cam))
  {
    t.setDistortionKannalaBrandt(fe->k1(), fe->k2(), fe->k3(), fe->k4());
    return t;
  }
  return std::nullopt;
}

CCameraModel::Ptr loadCameraFromConfig(
    const mrpt::config::CConfigFileBase& cfg, const std::string& section)
{
  const CSectionReader r(cfg, section);
  if (!cfg.sectionExists(section)) throw std::runtime_error(r.where() + " not found");

  if (r.has("calib_file"))
  {
    const std::string path = r.str("calib_file");
    if (path.empty()) r.fail("calib_file", "empty path");
    try
    {
      return loadCalibFile(path);
    }
    catch (const std::runtime_error& e)
    {
      r.fail("calib_file", e.what());
    }
  }

  if (!r.has("resolution")) throw std::runtime_error(r.where() + ": missing key 'resolution'");
  const std::vector<double> res = r.list("resolution");
  if (res.size() != 2 || !(res[0] >= 1 && res[1] >= 1 && res[0] <= INT_MAX && res[1] <= INT_MAX) ||
      res[0] != std::floor(res[0]) || res[1] != std::floor(res[1]))
    r.fail("resolution", "expected [WIDTH HEIGHT] with positive integers, got '" +
                             r.str("resolution") + "'");
  const int w = static_cast<int>(res[0]), h = static_cast<int>(res[1]);

  double fx = r.requiredDouble("fx"), fy = r.requiredDouble("fy");
  double cx = r.requiredDouble("cx"), cy = r.requiredDouble("cy");
  // MRPT's TCamera convention: values below 2 are fractions of the image size.
  if (fx < 2.0) fx *= w;
  if (fy < 2.0) fy *= h;
  if (cx < 2.0) cx *= w;
  if (cy < 2.0) cy *= h;

  std::string model = math::toLower(r.str("model"));
  const std::vector<double> dist = r.list("dist");
  const bool explicitModel = !model.empty();
  if (!explicitModel) model = modelFromDistortion(r, dist);

  try
  {
    if (model == "pinhole")
    {
      if (explicitModel && !allZero(dist)) r.fail("dist", "model = pinhole but the coefficients are not all zero");
      return std::make_shared<CPinholeCamera>(w, h, fx, fy, cx, cy);
    }
    if (model == "opencv")
    {
      if (!r.has("dist"))
        throw std::runtime_error(r.where() + ": missing key 'dist' (model = opencv)");
      const std::vector<double> k = plumbBob(dist, r);
      return std::make_shared<COpenCVCamera>(w, h, fx, fy, cx, cy, k[0], k[1], k[2], k[3], k[4]);
    }
    if (model == "davison")
      return std::make_shared<CDavisonCamera>(w, h, fx, fy, cx, cy, r.requiredDouble("kd1"));
    if (model == "fisheye")
    {
      // MRPT's order for kannala_brandt: dist = [k1 k2 k3 k4].
      if (!r.has("dist")) throw std::runtime_error(r.where() + ": missing key 'dist' (" + model + ": [k1 k2 k3 k4])");
      if (dist.size() != 4)
        r.fail("dist", "expected 4 coefficients [k1 k2 k3 k4] for the fisheye (kannala_brandt) model, got " +
                           std::to_string(dist.size()));
      return std::make_shared<CFisheyeCamera>(w, h, fx, fy, cx, cy, dist[0], dist[1], dist[2], dist[3]);
    }
  }
  catch (const std::runtime_error& e)
  {
    const std::string msg = e.what();
    if (msg.rfind(r.where(), 0) == 0) throw;
    throw std::runtime_error(r.where() + ": " + msg);
  }
  r.fail("model", "unknown value '" + model + "' (expected pinhole, opencv, davison or fisheye)");
}

std::vector<std::string> cameraConfigKeys()
{
  return {"calib_file", "model", "resolution", "fx", "fy", "cx", "cy", "dist", "distortion_model",
      "kd1", "camera_name", "focal_length"};
}
}  // namespace immslam::camera
