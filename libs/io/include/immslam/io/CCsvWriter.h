/* imm-monoslam — small CSV writer for the output files (model_probabilities.csv, frame_stats.csv...). */
#pragma once

#include <cstdint>
#include <fstream>
#include <string>
#include <type_traits>
#include <vector>

namespace immslam::io
{
/** One CSV cell: an integer, a floating-point number or a text. */
class CCsvCell
{
 public:
  /** Kind of value held. */
  enum class EKind
  {
    Integer,
    Real,
    Text
  };

  template <typename T, std::enable_if_t<std::is_integral_v<T> && !std::is_same_v<T, bool>, int> = 0>
  CCsvCell(T v) : m_kind(EKind::Integer), m_int(static_cast<long long>(v))
  {
  }
  CCsvCell(bool v) : m_kind(EKind::Integer), m_int(v ? 1 : 0) {}
  CCsvCell(double v) : m_kind(EKind::Real), m_real(v) {}
  CCsvCell(float v) : m_kind(EKind::Real), m_real(v) {}
  CCsvCell(std::string v) : m_kind(EKind::Text), m_text(std::move(v)) {}
  CCsvCell(const char* v) : m_kind(EKind::Text), m_text(v) {}

  EKind kind() const { return m_kind; }
  long long integer() const { return m_int; }
  double real() const { return m_real; }
  const std::string& text() const { return m_text; }

 private:
  EKind m_kind;
  long long m_int = 0;
  double m_real = 0;
  std::string m_text;
};

/** Writes a CSV file: the header on construction, then one addRow() per line.
 *
 * Formatting: columns named `timestamp` (or ending in `_timestamp`) print real values with `%.6f`
 * (the contract: at least 6 decimals, joinable with ground truth); other real values use `%.9g`
 * (nan/inf as `nan`, `inf`, `-inf`); integers exactly; texts as they are, quoted (RFC 4180) only if
 * they contain a comma, quote or newline.
 *
 * Example:
 * \code
 * io::CCsvWriter csv(out + "/model_probabilities.csv", {"timestamp", "stationary", "general_1px"});
 * csv.addRow({t, mu[0], mu[1]});           // all doubles
 * csv.addRow(t, 12, "static", 3.5);        // mixed cells (variadic)
 * csv.addCells(cells);                     // mixed cells built at run time
 * \endcode */
class CCsvWriter
{
 public:
  /** Creates (truncates) `path` and writes the header line.
   * \throws std::runtime_error naming the file if it cannot be opened or the header is empty. */
  CCsvWriter(const std::string& path, const std::vector<std::string>& columns);
  /** Flushes (never throws). */
  ~CCsvWriter();
  CCsvWriter(const CCsvWriter&) = delete;
  CCsvWriter& operator=(const CCsvWriter&) = delete;

  /** Appends a row of numbers. \throws std::runtime_error naming the file and row if the number
   * of values differs from the number of columns, or on a write error. */
  void addRow(const std::vector<double>& values);
  /** Appends a row of mixed cells (same checks). */
  void addCells(const std::vector<CCsvCell>& cells);
  /** Appends a row from any mix of numbers and strings: `addRow(t, n, "static", x)`. */
  template <typename First, typename... Rest,
            std::enable_if_t<!std::is_same_v<std::decay_t<First>, std::vector<double>> &&
                                 !std::is_same_v<std::decay_t<First>, std::vector<CCsvCell>>,
                             int> = 0>
  void addRow(const First& first, const Rest&... rest)
  {
    addCells(std::vector<CCsvCell>{CCsvCell(first), CCsvCell(rest)...});
  }

  /** Flushes to disk. \throws std::runtime_error naming the file on a write error. */
  void flush();

  const std::string& path() const { return m_path; }
  const std::vector<std::string>& columns() const { return m_columns; }
  /** Data rows written so far (the header excluded). */
  std::size_t rowCount() const { return m_rows; }

 private:
  std::string m_path;
  std::vector<std::string> m_columns;
  std::vector<bool> m_isTimestamp;
  std::ofstream m_out;
  std::size_t m_rows = 0;
};
}  // namespace immslam::io
