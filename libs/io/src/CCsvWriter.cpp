/* imm-monoslam — CSV writer. */
#include <immslam/io/CCsvWriter.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace immslam::io
{
namespace
{
bool isTimestampColumn(const std::string& name)
{
  static const std::string suffix = "_timestamp";
  return name == "timestamp" ||
         (name.size() > suffix.size() && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0);
}

std::string formatReal(double v, bool timestamp)
{
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[64];
  std::snprintf(buf, sizeof(buf), timestamp ? "%.6f" : "%.9g", v);
  return buf;
}

std::string quoteIfNeeded(const std::string& s)
{
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string q = "\"";
  for (const char c : s)
  {
    if (c == '"') q += '"';
    q += c;
  }
  return q + "\"";
}
}  // namespace

CCsvWriter::CCsvWriter(const std::string& path, const std::vector<std::string>& columns)
    : m_path(path), m_columns(columns)
{
  if (columns.empty()) throw std::runtime_error("CSV file " + path + ": no columns given");
  m_out.open(path, std::ios::trunc);
  if (!m_out) throw std::runtime_error("cannot write CSV file " + path);
  for (std::size_t i = 0; i < columns.size(); ++i)
  {
    m_isTimestamp.push_back(isTimestampColumn(columns[i]));
    m_out << (i ? "," : "") << quoteIfNeeded(columns[i]);
  }
  m_out << '\n';
  if (!m_out) throw std::runtime_error("write error in CSV file " + path);
}

CCsvWriter::~CCsvWriter()
{
  if (m_out.is_open()) m_out.flush();
}

void CCsvWriter::addRow(const std::vector<double>& values)
{
  addCells(std::vector<CCsvCell>(values.begin(), values.end()));
}

void CCsvWriter::addCells(const std::vector<CCsvCell>& cells)
{
  if (cells.size() != m_columns.size())
    throw std::runtime_error("CSV file " + m_path + ", data row " + std::to_string(m_rows + 1) + ": " +
                             std::to_string(cells.size()) + " values for " + std::to_string(m_columns.size()) +
                             " columns");
  std::string line;
  for (std::size_t i = 0; i < cells.size(); ++i)
  {
    if (i) line += ',';
    const CCsvCell& c = cells[i];
    switch (c.kind())
    {
      case CCsvCell::EKind::Integer: line += std::to_string(c.integer()); break;
      case CCsvCell::EKind::Real: line += formatReal(c.real(), m_isTimestamp[i]); break;
      case CCsvCell::EKind::Text: line += quoteIfNeeded(c.text()); break;
    }
  }
  line += '\n';
  m_out << line;
  if (!m_out) throw std::runtime_error("write error in CSV file " + m_path);
  ++m_rows;
}

void CCsvWriter::flush()
{
  m_out.flush();
  if (!m_out) throw std::runtime_error("write error in CSV file " + m_path);
}
}  // namespace immslam::io
