/* imm-monoslam — internal text-table reader of the evaluation's file readers. */
#include "table_reader.h"

#include <immslam/math/text.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <iterator>
#include <stdexcept>
#include <string_view>

namespace immslam::eval::detail
{
namespace
{
bool isBlank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

std::vector<std::string> splitWhitespace(const std::string& line)
{
  std::vector<std::string> out;
  std::size_t i = 0;
  while (i < line.size())
  {
    while (i < line.size() && isBlank(line[i])) ++i;
    if (i >= line.size()) break;
    std::size_t j = i;
    while (j < line.size() && !isBlank(line[j])) ++j;
    out.push_back(line.substr(i, j - i));
    i = j;
  }
  return out;
}

std::vector<std::string> splitCsv(const std::string& line)
{
  std::vector<std::string> out;
  std::string cur;
  bool quoted = false, wasQuoted = false;
  for (std::size_t i = 0; i < line.size(); ++i)
  {
    const char c = line[i];
    if (quoted)
    {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"')
        cur += '"', ++i;
      else if (c == '"')
        quoted = false;
      else
        cur += c;
    }
    else if (c == '"' && math::trim(cur).empty())
      quoted = wasQuoted = true, cur.clear();
    else if (c == ',')
    {
      out.push_back(wasQuoted ? cur : math::trim(cur));
      cur.clear();
      wasQuoted = false;
    }
    else if (!(wasQuoted && isBlank(c)))
      cur += c;
  }
  out.push_back(wasQuoted ? cur : math::trim(cur));
  return out;
}
}  // namespace

bool parseDouble(const std::string& s, double& v)
{
  std::string_view t(s);
  if (!t.empty() && t.front() == '+') t.remove_prefix(1);
  if (t.empty()) return false;
  const auto r = std::from_chars(t.data(), t.data() + t.size(), v);
  return r.ec == std::errc() && r.ptr == t.data() + t.size();
}

CTableReader::CTableReader(const std::string& path, ESeparator sep, const std::string& what)
    : m_path(path), m_sep(sep), m_in(path)
{
  if (!m_in) throw std::runtime_error(path + ": cannot open " + what);
}

bool CTableReader::next()
{
  std::string line;
  while (std::getline(m_in, line))
  {
    ++m_lineNo;
    const std::string t = math::trim(line);
    if (t.empty() || t.front() == '#') continue;
    m_fields = m_sep == ESeparator::Comma ? splitCsv(t) : splitWhitespace(t);
    return true;
  }
  if (m_in.bad()) throw std::runtime_error(m_path + ": read error");
  m_fields.clear();
  return false;
}

std::string CTableReader::where() const { return m_path + ":" + std::to_string(m_lineNo); }

void CTableReader::fail(const std::string& msg) const { throw std::runtime_error(where() + ": " + msg); }

void CTableReader::requireFields(std::size_t n, const std::string& columns) const
{
  if (m_fields.size() != n)
    fail("expected " + std::to_string(n) + " fields (" + columns + "), got " + std::to_string(m_fields.size()));
}

double CTableReader::anyNumber(std::size_t i, const std::string& column) const
{
  double v = 0;
  if (i >= m_fields.size() || !parseDouble(m_fields[i], v))
    fail(column + ": '" + (i < m_fields.size() ? m_fields[i] : std::string()) + "' is not a number");
  return v;
}

double CTableReader::number(std::size_t i, const std::string& column) const
{
  const double v = anyNumber(i, column);
  if (!std::isfinite(v)) fail(column + " is not finite");
  return v;
}

std::int64_t CTableReader::integer(std::size_t i, const std::string& column) const
{
  std::int64_t v = 0;
  const std::string_view s = i < m_fields.size() ? std::string_view(m_fields[i]) : std::string_view();
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || r.ec != std::errc() || r.ptr != s.data() + s.size())
    fail(column + ": '" + std::string(s) + "' is not an integer");
  return v;
}

std::ptrdiff_t nearestTime(const std::vector<double>& sortedTimes, double t, double maxDt)
{
  if (sortedTimes.empty() || !std::isfinite(t)) return -1;
  const auto it = std::lower_bound(sortedTimes.begin(), sortedTimes.end(), t);
  std::ptrdiff_t best = -1;
  double bestD = maxDt;
  const auto consider = [&](std::vector<double>::const_iterator c) {
    const double d = std::abs(*c - t);
    if (d <= bestD) bestD = d, best = c - sortedTimes.begin();
  };
  if (it != sortedTimes.end()) consider(it);
  if (it != sortedTimes.begin()) consider(std::prev(it));
  return best;
}
}  // namespace immslam::eval::detail
