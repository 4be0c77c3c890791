/* imm-monoslam — comma-separated number lists of the sim command lines (imm-composite, imm-rotate). */
#pragma once

#include <cmath>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

namespace immslam::sim
{
/** Parses "1,2.5,3" into v (cleared first). \return false for an empty item, a non-number or a
 * non-finite value. */
inline bool parseNumberList(const std::string& s, std::vector<double>& v)
{
  v.clear();
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ','))
  {
    char* end = nullptr;
    const double x = std::strtod(item.c_str(), &end);
    if (item.empty() || *end != '\0' || !std::isfinite(x)) return false;
    v.push_back(x);
  }
  return true;
}

/** parseNumberList() that also requires exactly n numbers. */
inline bool parseNumbers(const std::string& s, std::size_t n, std::vector<double>& v)
{
  return parseNumberList(s, v) && v.size() == n;
}
}  // namespace immslam::sim
