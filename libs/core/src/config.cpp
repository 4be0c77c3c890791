/* imm-monoslam — strict configuration reading. */
#include <immslam/core/config.h>
#include <immslam/math/text.h>
#include <mrpt/config/CConfigFileMemory.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <map>
#include <sstream>
#include <stdexcept>

namespace immslam::core
{
namespace
{
/** The raw value text, or nullopt-like empty flag when the key is absent. */
bool rawValue(const mrpt::config::CConfigFileBase& c, const std::string& section, const std::string& key, std::string& out)
{
  if (!c.keyExists(section, key)) return false;
  out = math::trim(c.read_string(section, key, ""));
  // Strip trailing comments that MRPT's parser keeps: "// ..." and " # ..." (a '#' after a blank).
  const auto cpos = out.find("//");
  if (cpos != std::string::npos) out = math::trim(out.substr(0, cpos));
  for (std::size_t i = 1; i < out.size(); ++i)
    if (out[i] == '#' && (out[i - 1] == ' ' || out[i - 1] == '\t'))
    {
      out = math::trim(out.substr(0, i));
      break;
    }
  if (!out.empty() && out[0] == '#') out.clear();
  return true;
}

[[noreturn]] void bad(const std::string& section, const std::string& key, const std::string& value, const std::string& what)
{
  throw std::runtime_error("[" + section + "] " + key + " = '" + value + "': " + what);
}

double parseNumber(const std::string& section, const std::string& key, const std::string& v)
{
  // std::from_chars: the whole text as a decimal number, whatever the process locale (std::stod
  // follows LC_NUMERIC, so "0.5" would not parse under a decimal-comma locale, and it accepted hex).
  const char* b = v.data();
  const char* e = v.data() + v.size();
  if (b != e && *b == '+' && (e - b) > 1 && b[1] != '-') ++b;
  double d = 0;
  const auto res = std::from_chars(b, e, d, std::chars_format::general);
  if (res.ec == std::errc::result_out_of_range && res.ptr == e) bad(section, key, v, "out of the range of a double");
  if (res.ec != std::errc() || res.ptr != e || v.empty()) bad(section, key, v, "not a number");
  if (std::isnan(d)) bad(section, key, v, "NaN is not allowed");
  return d;
}

std::size_t editDistance(const std::string& a, const std::string& b)
{
  std::vector<std::size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i)
  {
    cur[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j)
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
    std::swap(prev, cur);
  }
  return prev[b.size()];
}
}  // namespace

double readDouble(const mrpt::config::CConfigFileBase& c, const std::string& section, const std::string& key, double def)
{
  std::string v;
  if (!rawValue(c, section, key, v) || v.empty()) return def;
  return parseNumber(section, key, v);
}

int readInt(const mrpt::config::CConfigFileBase& c, const std::string& section, const std::string& key, int def)
{
  std::string v;
  if (!rawValue(c, section, key, v) || v.empty()) return def;
  const double d = parseNumber(section, key, v);
  if (d != std::floor(d) || std::abs(d) > 2e9) bad(section, key, v, "not an integer");
  return static_cast<int>(d);
}

bool readBool(const mrpt::config::CConfigFileBase& c, const std::string& section, const std::string& key, bool def)
{
  std::string v;
  if (!rawValue(c, section, key, v) || v.empty()) return def;
  std::string l = v;
  std::transform(l.begin(), l.end(), l.begin(), [](unsigned char ch) { return std::tolower(ch); });
  if (l == "true" || l == "1" || l == "yes" || l == "on") return true;
  if (l == "false" || l == "0" || l == "no" || l == "off") return false;
  bad(section, key, v, "not a boolean (true/false)");
}

std::string readString(const mrpt::config::CConfigFileBase& c, const std::string& section, const std::string& key,
                       const std::string& def)
{
  std::string v;
  if (!rawValue(c, section, key, v)) return def;
  return v;
}

std::vector<double> readVector(const mrpt::config::CConfigFileBase& c, const std::string& section,
                               const std::string& key, const std::vector<double>& def)
{
  std::string v;
  if (!rawValue(c, section, key, v) || v.empty()) return def;
  std::string t = v;
  for (char& ch : t)
    if (ch == '[' || ch == ']' || ch == ',' || ch == ';') ch = ' ';
  std::istringstream is(t);
  std::vector<double> out;
  std::string tok;
  while (is >> tok) out.push_back(parseNumber(section, key, tok));
  return out;
}

std::set<std::string> knownKeys(const mrpt::config::CLoadableOptions& opts, const std::string& section)
{
  mrpt::config::CConfigFileMemory mem;
  opts.saveToConfigFile(mem, section);
  std::vector<std::string> keys;
  mem.getAllKeys(section, keys);
  std::set<std::string> out;
  for (const auto& k : keys) out.insert(math::trim(k));  // MRPT pads saved names
  return out;
}

void checkKnownKeys(const mrpt::config::CConfigFileBase& c, const std::string& section, const std::set<std::string>& known)
{
  if (!c.sectionExists(section)) return;
  std::vector<std::string> keys;
  c.getAllKeys(section, keys);
  std::ostringstream err;
  int nBad = 0;
  for (const auto& kRaw : keys)
  {
    const std::string k = math::trim(kRaw);
    if (known.count(k)) continue;
    std::string best;
    std::size_t bestD = 1000;
    for (const auto& kk : known)
      if (const auto d = editDistance(k, kk); d < bestD) bestD = d, best = kk;
    err << (nBad++ ? "; " : "") << "unknown key [" << section << "] " << k;
    if (bestD <= 3) err << " (did you mean '" << best << "'?)";
  }
  if (nBad) throw std::runtime_error(err.str());
}

void checkIniSyntax(const std::string& text, const std::string& origin)
{
  std::istringstream in(text);
  std::string raw, section;
  bool inSection = false;
  std::map<std::string, std::size_t> seen;  // keys of the current section -> line
  for (std::size_t lineNo = 1; std::getline(in, raw); ++lineNo)
  {
    const std::string line = math::trim(raw);
    const auto where = [&] { return origin + ":" + std::to_string(lineNo) + ": "; };
    const auto shown = [&] {
      std::string t = line.size() > 60 ? line.substr(0, 60) + "..." : line;
      for (char& ch : t)
        if (static_cast<unsigned char>(ch) < 32 || static_cast<unsigned char>(ch) > 126) ch = '?';
      return "'" + t + "'";
    };
    if (line.empty() || line[0] == '#' || line[0] == ';' || line.rfind("//", 0) == 0 || line[0] == '@') continue;
    if (line[0] == '[')
    {
      const auto close = line.find(']');
      const std::string rest = close == std::string::npos ? std::string() : math::trim(line.substr(close + 1));
      if (close == std::string::npos || math::trim(line.substr(1, close - 1)).empty() ||
          !(rest.empty() || rest[0] == '#' || rest[0] == ';' || rest.rfind("//", 0) == 0))
        throw std::runtime_error(where() + "malformed section header " + shown() + " (expected [name])");
      section = math::trim(line.substr(1, close - 1));
      inSection = true;
      seen.clear();
      continue;
    }
    const auto eq = line.find('=');
    if (eq == std::string::npos)
      throw std::runtime_error(where() + shown() + " is not 'key = value' (missing '='?)");
    const std::string key = math::trim(line.substr(0, eq));
    if (key.empty()) throw std::runtime_error(where() + shown() + ": no key before '='");
    if (key.find_first_of(" \t[]") != std::string::npos)
      throw std::runtime_error(where() + "malformed key '" + key + "' in " + shown());
    if (!inSection)
      throw std::runtime_error(where() + "key '" + key + "' outside any [section]");
    const auto [it, fresh] = seen.emplace(key, lineNo);
    if (!fresh)
      throw std::runtime_error(where() + "[" + section + "] " + key + " given twice (also on line " +
                               std::to_string(it->second) + ")");
  }
}

void requirePositive(double v, const std::string& section, const std::string& key)
{
  if (!(v > 0) || !std::isfinite(v))
    throw std::runtime_error("[" + section + "] " + key + " = " + std::to_string(v) + ": must be a finite number > 0");
}

void requireNonNegative(double v, const std::string& section, const std::string& key)
{
  if (!(v >= 0) || !std::isfinite(v))
    throw std::runtime_error("[" + section + "] " + key + " = " + std::to_string(v) + ": must be a finite number >= 0");
}

void requireInRange(double v, double lo, double hi, const std::string& section, const std::string& key)
{
  if (!(v >= lo && v <= hi))
  {
    std::ostringstream s;
    s << "[" << section << "] " << key << " = " << v << ": must be in [" << lo << ", " << hi << "]";
    throw std::runtime_error(s.str());
  }
}
}  // namespace immslam::core
