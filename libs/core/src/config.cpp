/* imm-monoslam — strict configuration reading. */
#include <immslam/core/config.h>
#include <mrpt/config/CConfigFileMemory.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace immslam::core
{
namespace
{
std::string trim(const std::string& s)
{
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return {};
  const auto e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

/** The raw value text, or nullopt-like empty flag when the key is absent. */
bool rawValue(const mrpt::config::CConfigFileBase& c, const std::string& section, const std::string& key, std::string& out)
{
  if (!c.keyExists(section, key)) return false;
  out = trim(c.read_string(section, key, ""));
  // Strip trailing comments that MRPT's parser keeps: "// ..." and " # ..." (a '#' after a blank).
  const auto cpos = out.find("//");
  if (cpos != std::string::npos) out = trim(out.substr(0, cpos));
  for (std::size_t i = 1; i < out.size(); ++i)
    if (out[i] == '#' && (out[i - 1] == ' ' || out[i - 1] == '\t'))
    {
      out = trim(out.substr(0, i));
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
  std::size_t pos = 0;
  double d = 0;
  try
  {
    d = std::stod(v, &pos);
  }
  catch (const std::exception&)
  {
    bad(section, key, v, "not a number");
  }
  if (pos != v.size()) bad(section, key, v, "not a number");
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
  for (const auto& k : keys) out.insert(trim(k));  // MRPT pads saved names
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
    const std::string k = trim(kRaw);
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
