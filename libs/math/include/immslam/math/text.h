/* imm-monoslam — small text helpers shared by every parser (calib.txt, rgb.txt, ini, scenarios).
 * They live in the root module so that no parser needs another module for them. */
#pragma once

#include <cctype>
#include <string>

namespace immslam::math
{
/** \p s without leading and trailing blanks (space, tab, CR, LF, VT, FF). */
inline std::string trim(const std::string& s)
{
  constexpr const char* kBlanks = " \t\r\n\v\f";
  const auto b = s.find_first_not_of(kBlanks);
  if (b == std::string::npos) return {};
  const auto e = s.find_last_not_of(kBlanks);
  return s.substr(b, e - b + 1);
}

/** \p s in lower case (ASCII). */
inline std::string toLower(std::string s)
{
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}
}  // namespace immslam::math
