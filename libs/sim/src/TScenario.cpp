/* imm-monoslam — scenario ini parsing with strict key validation (see TScenario.h). */
#include <immslam/sim/TScenario.h>
#include <immslam/math/text.h>

#include <mrpt/config/CConfigFileMemory.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

namespace immslam::sim
{
namespace
{
/** Shortest decimal text that reads back to exactly v. */
std::string fmt(double v)
{
  char buf[64];
  for (int prec = 6; prec <= 17; ++prec)
  {
    std::snprintf(buf, sizeof(buf), "%.*g", prec, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  return buf;
}

std::string fmtVec(const double* v, int n)
{
  std::string s = "[";
  for (int i = 0; i < n; ++i) s += (i ? " " : "") + fmt(v[i]);
  return s + "]";
}

const std::map<std::string, std::set<std::string>>& allowedKeys()
{
  static const std::map<std::string, std::set<std::string>> k = {
      {"scenario", {"camera", "fps", "seed", "start_time_s", "threads"}},
      {"render",
       {"noise_sigma_grey", "blur_sigma_px", "colour", "texels_per_unit", "shapes_per_unit2", "object_shapes_per_unit2",
        "object_texels_per_unit"}},
      {"world",
       {"room_min", "room_max", "n_boxes", "box_size_min", "box_size_max", "wall_box_fraction",
        "keep_out"}},
      {"motion",
       {"segments", "ramp_s", "amplitude_units", "amplitude_deg", "max_speed_units_s", "max_rate_deg_s", "freq_hz", "n_sinusoids",
        "min_clearance"}},
      {"objects", {"enabled"}},
      {"object",
       {"size", "path", "center", "direction", "amplitude", "period_s", "phase_deg", "yaw_deg",
        "spin_deg_s", "start_s"}}};
  return k;
}

/** Object id of a section name "objectK" (K = 1..254), or 0. */
int objectSectionId(const std::string& sectionLower)
{
  if (sectionLower.rfind("object", 0) != 0 || sectionLower.size() == 6 || sectionLower == "objects")
    return 0;
  const std::string num = sectionLower.substr(6);
  if (!std::all_of(num.begin(), num.end(), [](char c) { return std::isdigit(static_cast<unsigned char>(c)); }))
    return 0;
  if (num.size() > 3) return 0;
  const int id = std::stoi(num);
  return (id >= 1 && id <= 254) ? id : 0;
}

/** Strict typed access to one section, errors naming origin, section and key. */
class CSectionReader
{
 public:
  CSectionReader(const mrpt::config::CConfigFileBase& cfg, std::string origin, std::string section,
                 const std::set<std::string>& presentKeysLower)
      : m_cfg(cfg), m_origin(std::move(origin)), m_section(std::move(section)), m_present(presentKeysLower)
  {
  }

  bool has(const std::string& key) const { return m_present.count(key) > 0; }

  [[noreturn]] void fail(const std::string& key, const std::string& value, const std::string& what) const
  {
    throw std::runtime_error(m_origin + ": [" + m_section + "] " + key + " = '" + value + "': " + what);
  }

  /** Raw value without inline '#'/';' comments, or "" when absent. */
  std::string raw(const std::string& key) const
  {
    if (!has(key)) return {};
    std::string v = m_cfg.read_string(m_section, key, "");
    const auto c = v.find_first_of("#;");
    if (c != std::string::npos) v.resize(c);
    return math::trim(v);
  }

  std::string str(const std::string& key, const std::string& def) const
  {
    return has(key) ? raw(key) : def;
  }

  double number(const std::string& key, double def) const
  {
    if (!has(key)) return def;
    return parseNumber(key, raw(key), raw(key));
  }

  int integer(const std::string& key, int def) const
  {
    const double v = number(key, def);
    if (v != std::floor(v) || std::abs(v) > 1e9) fail(key, raw(key), "expected an integer");
    return static_cast<int>(v);
  }

  std::uint64_t u64(const std::string& key, std::uint64_t def) const
  {
    if (!has(key)) return def;
    const std::string v = raw(key);
    char* end = nullptr;
    errno = 0;
    const unsigned long long x = std::strtoull(v.c_str(), &end, 10);
    if (v.empty() || v[0] == '-' || *end != '\0' || errno != 0) fail(key, v, "expected a non-negative integer");
    return x;
  }

  bool boolean(const std::string& key, bool def) const
  {
    if (!has(key)) return def;
    const std::string v = math::toLower(raw(key));
    if (v == "true" || v == "1" || v == "yes" || v == "on") return true;
    if (v == "false" || v == "0" || v == "no" || v == "off") return false;
    fail(key, raw(key), "expected true or false");
  }

  template <int N>
  Eigen::Matrix<double, N, 1> vec(const std::string& key, const Eigen::Matrix<double, N, 1>& def) const
  {
    if (!has(key)) return def;
    const std::string v = raw(key);
    std::string s = v;
    for (auto& c : s)
      if (c == '[' || c == ']' || c == ',') c = ' ';
    std::istringstream is(s);
    std::vector<double> vals;
    std::string tok;
    while (is >> tok) vals.push_back(parseNumber(key, tok, v));
    if (static_cast<int>(vals.size()) != N)
      fail(key, v, "expected " + std::to_string(N) + " numbers, e.g. [" + std::string(N == 2 ? "1 2" : N == 3 ? "1 2 3" : "1 2 3 4") + "]");
    Eigen::Matrix<double, N, 1> out;
    for (int i = 0; i < N; ++i) out[i] = vals[static_cast<std::size_t>(i)];
    return out;
  }

  double parseNumber(const std::string& key, const std::string& tok, const std::string& whole) const
  {
    char* end = nullptr;
    const double x = std::strtod(tok.c_str(), &end);
    if (tok.empty() || *end != '\0' || !std::isfinite(x)) fail(key, whole, "expected a finite number");
    return x;
  }

  const std::string& section() const { return m_section; }
  const std::string& origin() const { return m_origin; }

 private:
  const mrpt::config::CConfigFileBase& m_cfg;
  std::string m_origin, m_section;
  std::set<std::string> m_present;
};

std::vector<TMotionSegment> parseSegments(const CSectionReader& r, const std::string& key)
{
  const std::string v = r.raw(key);
  std::vector<TMotionSegment> segs;
  std::istringstream all(v);
  std::string item;
  while (std::getline(all, item, ','))
  {
    std::istringstream is(item);
    std::string type, dur, extra;
    if (!(is >> type >> dur) || (is >> extra))
      r.fail(key, v, "each comma-separated item must be 'TYPE SECONDS' (TYPE stationary|rotation|general), got '" + math::trim(item) + "'");
    TMotionSegment s;
    s.type = motionLabelFromString(math::toLower(type), r.origin() + ": [" + r.section() + "] " + key);
    s.duration_s = r.parseNumber(key, dur, v);
    segs.push_back(s);
  }
  if (segs.empty()) r.fail(key, v, "no segments");
  return segs;
}

std::string segmentsText(const std::vector<TMotionSegment>& segs)
{
  std::string s;
  for (std::size_t i = 0; i < segs.size(); ++i)
    s += (i ? ", " : "") + toString(segs[i].type) + " " + fmt(segs[i].duration_s);
  return s;
}

/** The sections of a scenario file by lower-case name: (name as written, lower-case keys). */
using TPresentSections = std::map<std::string, std::pair<std::string, std::set<std::string>>>;

/** Every section and key of `cfg`, checked: unknown sections and keys, and repeated sections, are
 * errors naming them (prefixed by `origin`). */
TPresentSections presentSections(const mrpt::config::CConfigFileBase& cfg, const std::string& origin)
{
  std::vector<std::string> sections;
  cfg.getAllSections(sections);
  TPresentSections present;
  for (const auto& sec : sections)
  {
    const std::string sl = math::toLower(math::trim(sec));
    if (sl.empty()) continue;
    std::vector<std::string> keys;
    cfg.getAllKeys(sec, keys);
    const bool isObject = objectSectionId(sl) > 0;
    const auto it = allowedKeys().find(isObject ? "object" : sl);
    if (it == allowedKeys().end())
      throw std::runtime_error(origin + ": unknown section [" + sec +
                               "] (expected scenario, render, world, motion, objects, object1..object254)");
    if (present.count(sl)) throw std::runtime_error(origin + ": section [" + sec + "] appears twice");
    std::set<std::string> ks;
    for (const auto& k : keys)
    {
      const std::string kl = math::toLower(math::trim(k));
      if (!it->second.count(kl))
      {
        std::string allowed;
        for (const auto& a : it->second) allowed += (allowed.empty() ? "" : ", ") + a;
        throw std::runtime_error(origin + ": unknown key '" + k + "' in section [" + sec + "] (allowed: " + allowed + ")");
      }
      ks.insert(kl);
    }
    present[sl] = {sec, ks};
  }
  return present;
}

/** Section [objectN] (r) as the moving object of id N. */
TMovingObjectSpec readObject(const CSectionReader& r, int id)
{
  TMovingObjectSpec o;
  o.id = id;
  o.size = r.vec<3>("size", o.size);
  const std::string path = math::toLower(r.str("path", "linear"));
  if (path == "linear")
    o.path = EObjectPath::Linear;
  else if (path == "circular")
    o.path = EObjectPath::Circular;
  else
    r.fail("path", r.raw("path"), "expected linear or circular");
  o.center = r.vec<3>("center", o.center);
  o.direction = r.vec<3>("direction", o.direction);
  if (!(o.direction.norm() > 1e-9)) r.fail("direction", r.raw("direction"), "must be a non-zero vector");
  o.amplitude = r.number("amplitude", o.amplitude);
  o.period_s = r.number("period_s", o.period_s);
  o.phase_deg = r.number("phase_deg", o.phase_deg);
  o.start_s = r.number("start_s", o.start_s);
  o.yaw_deg = r.number("yaw_deg", o.yaw_deg);
  o.spin_deg_s = r.vec<3>("spin_deg_s", o.spin_deg_s);
  return o;
}
}  // namespace

std::string toString(EMotionLabel label)
{
  switch (label)
  {
    case EMotionLabel::Stationary: return "stationary";
    case EMotionLabel::Rotation: return "rotation";
    case EMotionLabel::General: return "general";
  }
  return "general";
}

EMotionLabel motionLabelFromString(const std::string& word, const std::string& context)
{
  if (word == "stationary") return EMotionLabel::Stationary;
  if (word == "rotation") return EMotionLabel::Rotation;
  if (word == "general") return EMotionLabel::General;
  throw std::runtime_error(context + ": unknown motion type '" + word +
                           "' (expected stationary, rotation or general)");
}

double TScenario::duration() const
{
  double d = 0;
  for (const auto& s : segments) d += s.duration_s;
  return d;
}

std::size_t TScenario::frameCount() const
{
  return static_cast<std::size_t>(std::floor(duration() * fps + 1e-6));
}

TScenario TScenario::fromConfig(const mrpt::config::CConfigFileBase& cfg, const std::string& origin)
{
  TScenario sc;
  sc.origin = origin;
  // Collect and validate every section and key.
  const TPresentSections present = presentSections(cfg, origin);
  const auto reader = [&](const std::string& sl) {
    const auto it = present.find(sl);
    static const std::set<std::string> none;
    return it == present.end() ? CSectionReader(cfg, origin, sl, none)
                               : CSectionReader(cfg, origin, it->second.first, it->second.second);
  };

  {
    const auto r = reader("scenario");
    if (!r.has("camera"))
      throw std::runtime_error(origin + ": missing key [scenario] camera (e.g. camera = pinhole 320 240 250 250 159.5 119.5)");
    sc.camera = camera::parseCalibLine(r.raw("camera"), origin + ": [scenario] camera");
    sc.fps = r.number("fps", sc.fps);
    sc.seed = r.u64("seed", sc.seed);
    sc.start_time_s = r.number("start_time_s", sc.start_time_s);
    sc.threads = r.integer("threads", sc.threads);
  }
  {
    const auto r = reader("render");
    sc.noise_sigma_grey = r.number("noise_sigma_grey", sc.noise_sigma_grey);
    sc.blur_sigma_px = r.number("blur_sigma_px", sc.blur_sigma_px);
    sc.colour = r.boolean("colour", sc.colour);
    sc.texels_per_unit = r.number("texels_per_unit", sc.texels_per_unit);
    sc.shapes_per_unit2 = r.number("shapes_per_unit2", sc.shapes_per_unit2);
    sc.object_shapes_per_unit2 = r.number("object_shapes_per_unit2", sc.object_shapes_per_unit2);
    sc.object_texels_per_unit = r.number("object_texels_per_unit", sc.object_texels_per_unit);
  }
  {
    const auto r = reader("world");
    sc.room_min = r.vec<3>("room_min", sc.room_min);
    sc.room_max = r.vec<3>("room_max", sc.room_max);
    sc.n_boxes = r.integer("n_boxes", sc.n_boxes);
    sc.box_size_min = r.vec<3>("box_size_min", sc.box_size_min);
    sc.box_size_max = r.vec<3>("box_size_max", sc.box_size_max);
    sc.wall_box_fraction = r.number("wall_box_fraction", sc.wall_box_fraction);
    sc.keep_out = r.vec<4>("keep_out", sc.keep_out);
  }
  {
    const auto r = reader("motion");
    if (!r.has("segments"))
      throw std::runtime_error(origin + ": missing key [motion] segments (e.g. segments = stationary 1, general 5)");
    sc.segments = parseSegments(r, "segments");
    sc.ramp_s = r.number("ramp_s", sc.ramp_s);
    sc.amplitude_units = r.vec<3>("amplitude_units", sc.amplitude_units);
    sc.amplitude_deg = r.vec<3>("amplitude_deg", sc.amplitude_deg);
    sc.max_speed_units_s = r.vec<3>("max_speed_units_s", sc.max_speed_units_s);
    sc.max_rate_deg_s = r.vec<3>("max_rate_deg_s", sc.max_rate_deg_s);
    sc.freq_hz = r.vec<2>("freq_hz", sc.freq_hz);
    sc.n_sinusoids = r.integer("n_sinusoids", sc.n_sinusoids);
    sc.min_clearance = r.number("min_clearance", sc.min_clearance);
  }
  {
    const auto r = reader("objects");
    sc.objects_enabled = r.boolean("enabled", sc.objects_enabled);
  }
  std::vector<int> ids;
  for (const auto& [sl, v] : present)
    if (const int id = objectSectionId(sl)) ids.push_back(id);
  std::sort(ids.begin(), ids.end());
  for (const int id : ids)
  {
    sc.objects.push_back(readObject(reader("object" + std::to_string(id)), id));
  }
  sc.validate();
  return sc;
}

void TScenario::validate() const
{
  const auto bad = [&](const std::string& where, const std::string& what) {
    throw std::runtime_error(origin + ": " + where + ": " + what);
  };
  if (!camera) bad("[scenario] camera", "missing");
  if (!(fps > 0 && fps <= 1000)) bad("[scenario] fps", "must be in (0, 1000]");
  if (threads < 0 || threads > 64) bad("[scenario] threads", "must be in [0, 64]");
  if (!(noise_sigma_grey >= 0 && noise_sigma_grey <= 100)) bad("[render] noise_sigma_grey", "must be in [0, 100]");
  if (!(blur_sigma_px >= 0 && blur_sigma_px <= 20)) bad("[render] blur_sigma_px", "must be in [0, 20]");
  if (!(texels_per_unit >= 8 && texels_per_unit <= 1000)) bad("[render] texels_per_unit", "must be in [8, 1000]");
  if (!(shapes_per_unit2 >= 0 && shapes_per_unit2 <= 10000)) bad("[render] shapes_per_unit2", "must be in [0, 10000]");
  if (!(object_shapes_per_unit2 >= 0 && object_shapes_per_unit2 <= 10000))
    bad("[render] object_shapes_per_unit2", "must be in [0, 10000]");
  if (!(object_texels_per_unit >= 10 && object_texels_per_unit <= 4000))
    bad("[render] object_texels_per_unit", "must be in [10, 4000]");
  if (!((room_max - room_min).minCoeff() > 0)) bad("[world] room_max", "must exceed room_min on every axis");
  if ((room_max - room_min).maxCoeff() > 200) bad("[world] room_max", "room larger than 200 units");
  if (!(room_min.array() + min_clearance < 0).all() || !(room_max.array() - min_clearance > 0).all())
    bad("[world] room_min/room_max", "the start camera position (the origin) must be inside the room, min_clearance from its faces");
  if (n_boxes < 0 || n_boxes > 40) bad("[world] n_boxes", "must be in [0, 40]");
  if (!(box_size_min.minCoeff() > 0)) bad("[world] box_size_min", "must be positive");
  if (!((box_size_max - box_size_min).minCoeff() >= 0)) bad("[world] box_size_max", "must be >= box_size_min");
  if (!(wall_box_fraction >= 0 && wall_box_fraction <= 1)) bad("[world] wall_box_fraction", "must be in [0, 1]");
  if (!(keep_out[2] > keep_out[0] && keep_out[3] > keep_out[1])) bad("[world] keep_out", "must be [x_min z_min x_max z_max] with max > min");
  if (segments.empty()) bad("[motion] segments", "no segments");
  for (const auto& s : segments)
    if (!(s.duration_s > 0 && s.duration_s < 1e5)) bad("[motion] segments", "durations must be positive");
  if (frameCount() < 1) bad("[motion] segments", "shorter than one frame");
  if (!(ramp_s >= 0 && ramp_s <= 10)) bad("[motion] ramp_s", "must be in [0, 10]");
  if (!(amplitude_units.minCoeff() >= 0 && amplitude_units.maxCoeff() <= 10)) bad("[motion] amplitude_units", "must be in [0, 10]");
  if (!(amplitude_deg.minCoeff() >= 0 && amplitude_deg.maxCoeff() <= 80)) bad("[motion] amplitude_deg", "must be in [0, 80]");
  if (!(max_speed_units_s.minCoeff() >= 0)) bad("[motion] max_speed_units_s", "must be >= 0");
  if (!(max_rate_deg_s.minCoeff() >= 0)) bad("[motion] max_rate_deg_s", "must be >= 0");
  if (!(freq_hz[0] > 0 && freq_hz[1] >= freq_hz[0] && freq_hz[1] <= 100)) bad("[motion] freq_hz", "must be [f_min f_max] with 0 < f_min <= f_max <= 100");
  if (n_sinusoids < 1 || n_sinusoids > 16) bad("[motion] n_sinusoids", "must be in [1, 16]");
  if (!(min_clearance >= 0 && min_clearance < 10)) bad("[motion] min_clearance", "must be in [0, 10)");
  if (n_boxes + static_cast<int>(objects.size()) > 62) bad("[world] n_boxes", "at most 62 boxes and moving objects in all");
  for (const auto& o : objects)
  {
    const std::string sec = "[object" + std::to_string(o.id) + "] ";
    if (!(o.size.minCoeff() > 0)) bad(sec + "size", "must be positive");
    if (!(o.amplitude >= 0)) bad(sec + "amplitude", "must be >= 0");
    if (!(o.period_s > 0)) bad(sec + "period_s", "must be positive");
    if (!(o.start_s >= 0 && o.start_s < 1e5)) bad(sec + "start_s", "must be in [0, 1e5) s");
    if (!(o.direction.norm() > 1e-9)) bad(sec + "direction", "must be a non-zero vector");
  }
}

TScenario TScenario::loadString(const std::string& text, const std::string& origin,
                                const std::vector<std::string>& overrides)
{
  mrpt::config::CConfigFileMemory cfg(text);
  for (const auto& o : overrides)
  {
    const auto dot = o.find('.');
    const auto eq = o.find('=');
    if (dot == std::string::npos || eq == std::string::npos || dot > eq || dot == 0 || eq == dot + 1)
      throw std::runtime_error("bad override '" + o + "': expected SECTION.KEY=VALUE");
    cfg.write(math::trim(o.substr(0, dot)), math::trim(o.substr(dot + 1, eq - dot - 1)), math::trim(o.substr(eq + 1)));
  }
  return fromConfig(cfg, origin);
}

TScenario TScenario::loadFile(const std::string& path, const std::vector<std::string>& overrides)
{
  std::ifstream f(path);
  if (!f) throw std::runtime_error("cannot read scenario file '" + path + "'");
  std::stringstream ss;
  ss << f.rdbuf();
  return loadString(ss.str(), path, overrides);
}

std::string TScenario::toIni() const
{
  std::ostringstream o;
  const auto kv = [&o](const std::string& key, const std::string& value, const std::string& comment) {
    if (!comment.empty()) o << "# " << comment << "\n";
    o << key << " = " << value << "\n";
  };
  const auto v3 = [](const Vec3& v) { return fmtVec(v.data(), 3); };
  o << "# imm-monoslam rendered scenario: the effective value of every key (imm-render reads it back).\n"
    << "# World frame W = the first camera frame: x right, y down, z forward; lengths in units.\n\n";
  o << "[scenario]\n";
  kv("camera", camera ? camera->toCalibLine() : std::string(), "camera model in calib.txt syntax: MODEL W H PARAMS...");
  kv("fps", fmt(fps), "frame rate (Hz)");
  kv("seed", std::to_string(seed), "master seed of every random choice");
  kv("start_time_s", fmt(start_time_s), "timestamp of the first frame (s)");
  kv("threads", std::to_string(threads), "render threads (0: all cores); the output does not depend on it");
  o << "\n[render]\n";
  kv("noise_sigma_grey", fmt(noise_sigma_grey), "Gaussian pixel noise (grey levels)");
  kv("blur_sigma_px", fmt(blur_sigma_px), "Gaussian blur before the noise (pixels)");
  kv("colour", colour ? "true" : "false", "also render colour (tinted faces); grey = its luminance");
  kv("texels_per_unit", fmt(texels_per_unit), "texture resolution");
  kv("shapes_per_unit2", fmt(shapes_per_unit2), "density of the texture shapes (per square unit)");
  kv("object_shapes_per_unit2", fmt(object_shapes_per_unit2), "the same on the moving objects");
  kv("object_texels_per_unit", fmt(object_texels_per_unit), "texture resolution of the moving objects");
  o << "\n[world]\n";
  kv("room_min", v3(room_min), "room corners in W (the floor is y = room_max.y)");
  kv("room_max", v3(room_max), "");
  kv("n_boxes", std::to_string(n_boxes), "static textured boxes placed at random");
  kv("box_size_min", v3(box_size_min), "edge length ranges of the static boxes (x, height, z)");
  kv("box_size_max", v3(box_size_max), "");
  kv("wall_box_fraction", fmt(wall_box_fraction), "fraction of the boxes hung on the walls");
  kv("keep_out", fmtVec(keep_out.data(), 4), "floor rectangle [x_min z_min x_max z_max] without static boxes");
  o << "\n[motion]\n";
  kv("segments", segmentsText(segments), "motion script: TYPE SECONDS, ... (TYPE stationary|rotation|general)");
  kv("ramp_s", fmt(ramp_s), "velocity ramps at segment changes (s)");
  kv("amplitude_units", v3(amplitude_units), "peak excursion of the hand-held path per world axis");
  kv("amplitude_deg", v3(amplitude_deg), "peak excursion of the orientation about camera x, y, z (deg)");
  kv("max_speed_units_s", v3(max_speed_units_s), "speed cap per world axis (units/s)");
  kv("max_rate_deg_s", v3(max_rate_deg_s), "rotation rate cap per camera axis (deg/s)");
  kv("freq_hz", fmtVec(freq_hz.data(), 2), "frequency range of the path's sinusoids (Hz)");
  kv("n_sinusoids", std::to_string(n_sinusoids), "sinusoids per axis");
  kv("min_clearance", fmt(min_clearance), "minimum distance of the camera to walls, boxes and moving objects");
  o << "\n[objects]\n";
  kv("enabled", objects_enabled ? "true" : "false", "render the moving objects [objectK] (K = mask value)");
  for (const auto& ob : objects)
  {
    o << "\n[object" << ob.id << "]\n";
    kv("size", v3(ob.size), "edge lengths (units)");
    kv("path", ob.path == EObjectPath::Linear ? "linear" : "circular",
       "linear: center + amplitude sin(2 pi t / period + phase) direction; circular: radius amplitude, normal direction");
    kv("center", v3(ob.center), "path centre in W");
    kv("direction", v3(ob.direction), "direction of travel (linear) or circle normal (circular)");
    kv("amplitude", fmt(ob.amplitude), "half travel (linear) or radius (circular)");
    kv("period_s", fmt(ob.period_s), "period (s)");
    kv("phase_deg", fmt(ob.phase_deg), "phase at t = 0 (deg)");
    kv("start_s", fmt(ob.start_s), "stands still until this time (s)");
    kv("yaw_deg", fmt(ob.yaw_deg), "initial rotation about the world y axis (deg)");
    kv("spin_deg_s", v3(ob.spin_deg_s), "angular velocity in W (deg/s)");
  }
  return o.str();
}
}  // namespace immslam::sim
