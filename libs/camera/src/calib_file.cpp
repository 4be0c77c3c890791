/* imm-monoslam — calib.txt: parsing, loading, saving, and the model factory. */
#include <immslam/camera/CCameraModel.h>
#include <immslam/camera/CDavisonCamera.h>
#include <immslam/camera/CFisheyeCamera.h>
#include <immslam/camera/COpenCVCamera.h>
#include <immslam/camera/CPinholeCamera.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace immslam::camera
{
namespace
{
/** A calib.txt model word and the names of its parameters after the image size. */
struct TModelSpec
{
  const char* name;
  std::vector<const char*> params;
};

const std::array<TModelSpec, 4>& modelSpecs()
{
  static const std::array<TModelSpec, 4> specs{{
      {"pinhole", {"fx", "fy", "cx", "cy"}},
      {"opencv", {"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3"}},
      {"davison", {"fx", "fy", "cx", "cy", "kd1"}},
      {"fisheye", {"fx", "fy", "cx", "cy", "k1", "k2", "k3", "k4"}},
  }};
  return specs;
}

const TModelSpec* findSpec(const std::string& model)
{
  for (const auto& s : modelSpecs())
    if (model == s.name) return &s;
  return nullptr;
}

/** "fx fy cx cy ..." of a model. */
std::string paramNames(const TModelSpec& spec)
{
  std::string out;
  for (const char* p : spec.params) out += (out.empty() ? "" : " ") + std::string(p);
  return out;
}

/** "WIDTH HEIGHT fx fy cx cy ..." of a model. */
std::string joinNames(const TModelSpec& spec) { return "WIDTH HEIGHT " + paramNames(spec); }

std::string unknownModelMessage(const std::string& model)
{
  return "unknown camera model '" + model + "' (expected pinhole, opencv, davison or fisheye)";
}

std::string stripComment(const std::string& line)
{
  std::string s = line.substr(0, line.find('#'));
  if (!s.empty() && s.back() == '\r') s.pop_back();
  return s;
}

std::string lower(std::string s)
{
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

/** Parses the whole word as a decimal double (locale independent); false if it is not one. */
bool parseDouble(const std::string& word, double& out)
{
  const char* end = word.data() + word.size();
  const auto res = std::from_chars(word.data(), end, out);
  return res.ec == std::errc() && res.ptr == end;
}

/** Parses the whole word as a decimal int; false if it is not one. */
bool parseInt(const std::string& word, int& out)
{
  const char* end = word.data() + word.size();
  const auto res = std::from_chars(word.data(), end, out);
  return res.ec == std::errc() && res.ptr == end;
}
}  // namespace

CCameraModel::Ptr pinholeFromFieldOfView(int width, int height, double hfovDeg)
{
  if (width <= 0 || height <= 0 || !(hfovDeg >= 1 && hfovDeg <= 179))
    throw std::invalid_argument("pinholeFromFieldOfView: need a positive image size and a field of view in [1, 179] "
                                "degrees, got " + std::to_string(width) + "x" + std::to_string(height) + ", " +
                                std::to_string(hfovDeg));
  const double f = 0.5 * width / std::tan(0.5 * hfovDeg * M_PI / 180.0);
  return makeCameraModel("pinhole", width, height, {f, f, 0.5 * (width - 1), 0.5 * (height - 1)});
}

CCameraModel::Ptr makeCameraModel(
    const std::string& model, int width, int height, const std::vector<double>& params)
{
  const TModelSpec* spec = findSpec(model);
  if (!spec) throw std::runtime_error(unknownModelMessage(model));
  if (params.size() != spec->params.size())
    throw std::runtime_error("camera model '" + model + "' needs " +
                             std::to_string(spec->params.size()) + " parameters after the size (" +
                             paramNames(*spec) + "), got " + std::to_string(params.size()));
  const auto& p = params;
  if (model == "pinhole") return std::make_shared<CPinholeCamera>(width, height, p[0], p[1], p[2], p[3]);
  if (model == "opencv")
    return std::make_shared<COpenCVCamera>(
        width, height, p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8]);
  if (model == "fisheye")
    return std::make_shared<CFisheyeCamera>(width, height, p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]);
  return std::make_shared<CDavisonCamera>(width, height, p[0], p[1], p[2], p[3], p[4]);
}

CCameraModel::Ptr parseCalibLine(const std::string& line, const std::string& context)
{
  std::istringstream ss(stripComment(line));
  std::vector<std::string> words;
  for (std::string w; ss >> w;) words.push_back(w);
  if (words.empty())
    throw std::runtime_error(context + ": empty calibration line (expected MODEL WIDTH HEIGHT PARAMS...)");

  const std::string model = lower(words[0]);
  const TModelSpec* spec = findSpec(model);
  if (!spec) throw std::runtime_error(context + ": " + unknownModelMessage(words[0]));
  const size_t nValues = 2 + spec->params.size();
  if (words.size() - 1 != nValues)
    throw std::runtime_error(context + ": model '" + model + "' needs " + std::to_string(nValues) +
                             " values after the model name (" + joinNames(*spec) + "), got " +
                             std::to_string(words.size() - 1));

  int size[2];
  const char* sizeNames[2] = {"width", "height"};
  for (int i = 0; i < 2; ++i)
    if (!parseInt(words[1 + i], size[i]) || size[i] <= 0)
      throw std::runtime_error(context + ": " + sizeNames[i] + " must be a positive integer, got '" +
                               words[1 + i] + "'");

  std::vector<double> params(spec->params.size());
  for (size_t i = 0; i < params.size(); ++i)
  {
    const std::string& w = words[3 + i];
    if (!parseDouble(w, params[i]))
      throw std::runtime_error(
          context + ": " + spec->params[i] + " = '" + w + "' is not a number");
    if (!std::isfinite(params[i]))
      throw std::runtime_error(context + ": " + spec->params[i] + " = '" + w + "' is not finite");
  }
  if (!(params[0] > 0)) throw std::runtime_error(context + ": fx must be positive, got '" + words[3] + "'");
  if (!(params[1] > 0)) throw std::runtime_error(context + ": fy must be positive, got '" + words[4] + "'");

  try
  {
    return makeCameraModel(model, size[0], size[1], params);
  }
  catch (const std::runtime_error& e)
  {
    throw std::runtime_error(context + ": " + e.what());
  }
}

CCameraModel::Ptr loadCalibFile(const std::string& path)
{
  std::ifstream f(path);
  if (!f) throw std::runtime_error("cannot open calibration file '" + path + "'");
  CCameraModel::Ptr cam;
  int modelLine = 0;
  std::string line;
  for (int lineNo = 1; std::getline(f, line); ++lineNo)
  {
    const std::string content = stripComment(line);
    if (content.find_first_not_of(" \t\v\f") == std::string::npos) continue;
    const std::string context = path + ":" + std::to_string(lineNo);
    if (cam)
      throw std::runtime_error(context + ": a second model line (the first is line " +
                               std::to_string(modelLine) + "); calib.txt holds exactly one");
    cam = parseCalibLine(content, context);
    modelLine = lineNo;
  }
  if (f.bad()) throw std::runtime_error("error reading calibration file '" + path + "'");
  if (!cam)
    throw std::runtime_error(
        path + ": no model line (expected one line MODEL WIDTH HEIGHT PARAMS..., MODEL one of "
               "pinhole, opencv, davison, fisheye)");
  return cam;
}

void saveCalibFile(const CCameraModel& cam, const std::string& path)
{
  const TModelSpec* spec = findSpec(cam.modelName());
  std::ofstream f(path);
  if (!f) throw std::runtime_error("cannot write calibration file '" + path + "'");
  f << "# model " << lower(spec ? joinNames(*spec) : std::string("WIDTH HEIGHT PARAMS..."))
    << "\n";
  f << cam.toCalibLine() << "\n";
  f.close();
  if (!f) throw std::runtime_error("error writing calibration file '" + path + "'");
}
}  // namespace immslam::camera
