/* imm-monoslam — internal: line-by-line reader of the small text tables the evaluation reads
 * (CSV outputs of the app, whitespace-separated truth files of the renderer and the shared data).
 * Not installed: a detail of libs/eval's readers. */
#pragma once

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

namespace immslam::eval::detail
{
/** Reads a text table one data line at a time. Blank lines and lines whose first non-blank
 * character is '#' are skipped. Fields are split on commas (CSV: surrounding blanks trimmed,
 * double-quoted fields with "" escapes unquoted) or on runs of blanks (whitespace tables).
 * Every error names `path:line`. */
class CTableReader
{
 public:
  enum class ESeparator
  {
    Comma,
    Whitespace
  };

  /** Opens the file. \param what a short description for the "cannot open" message.
   * \throws std::runtime_error naming the file when it cannot be opened. */
  CTableReader(const std::string& path, ESeparator sep, const std::string& what);

  /** Advances to the next data line; false at the end of the file. */
  bool next();

  /** Fields of the current line. */
  const std::vector<std::string>& fields() const { return m_fields; }
  /** 1-based number of the current line in the file. */
  std::size_t lineNo() const { return m_lineNo; }
  /** "path:line" of the current line. */
  std::string where() const;
  /** The file's path. */
  const std::string& path() const { return m_path; }

  /** Throws std::runtime_error("path:line: msg"). */
  [[noreturn]] void fail(const std::string& msg) const;
  /** Throws unless the current line has exactly n fields (message lists the expected columns). */
  void requireFields(std::size_t n, const std::string& columns) const;
  /** Field i as a finite double (locale independent). \throws naming the column. */
  double number(std::size_t i, const std::string& column) const;
  /** Field i as a double that may be nan or inf. */
  double anyNumber(std::size_t i, const std::string& column) const;
  /** Field i as an integer. */
  std::int64_t integer(std::size_t i, const std::string& column) const;

 private:
  std::string m_path;
  ESeparator m_sep;
  std::ifstream m_in;
  std::size_t m_lineNo = 0;
  std::vector<std::string> m_fields;
};

/** Parses a whole string as a double (locale independent, leading '+' allowed); false on any
 * leftover character. "nan" and "inf" parse. */
bool parseDouble(const std::string& s, double& v);

/** Index of the entry of sortedTimes nearest to t if it is within maxDt, else -1. */
std::ptrdiff_t nearestTime(const std::vector<double>& sortedTimes, double t, double maxDt);
}  // namespace immslam::eval::detail
