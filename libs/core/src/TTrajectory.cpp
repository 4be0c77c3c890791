/* imm-monoslam — TUM trajectory files. */
#include <immslam/core/TTrajectory.h>

#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <stdexcept>
#include <string_view>

namespace immslam::core
{
namespace
{
bool isSeparator(char c) { return c == ' ' || c == '\t' || c == ',' || c == '\r' || c == '\v' || c == '\f'; }

/** Parses a whole token as a double (locale independent); false on any leftover character. */
bool parseDouble(std::string_view tok, double& v)
{
  if (!tok.empty() && tok.front() == '+') tok.remove_prefix(1);
  if (tok.empty()) return false;
  const auto res = std::from_chars(tok.data(), tok.data() + tok.size(), v);
  return res.ec == std::errc() && res.ptr == tok.data() + tok.size();
}

void appendShortest(std::string& s, double v)
{
  std::array<char, 64> buf{};
  const auto res = std::to_chars(buf.data(), buf.data() + buf.size(), v);
  s.append(buf.data(), res.ptr);
}
}  // namespace

TTrajectory readTumTrajectory(const std::string& path)
{
  std::ifstream f(path);
  if (!f) throw std::runtime_error(path + ": cannot open trajectory file");
  TTrajectory traj;
  std::string line;
  size_t lineNo = 0;
  while (std::getline(f, line))
  {
    ++lineNo;
    const auto where = [&] { return path + ":" + std::to_string(lineNo) + ": "; };
    // Split into tokens.
    std::vector<std::string_view> tok;
    const std::string_view sv(line);
    size_t i = 0;
    while (i < sv.size())
    {
      while (i < sv.size() && isSeparator(sv[i])) ++i;
      if (i >= sv.size()) break;
      size_t j = i;
      while (j < sv.size() && !isSeparator(sv[j])) ++j;
      tok.push_back(sv.substr(i, j - i));
      i = j;
    }
    if (tok.empty() || tok.front().front() == '#') continue;
    if (tok.size() != 8)
      throw std::runtime_error(where() + "expected 8 numbers 'timestamp tx ty tz qx qy qz qw', got " +
                               std::to_string(tok.size()) + " fields");
    std::array<double, 8> v{};
    for (size_t k = 0; k < 8; ++k)
    {
      if (!parseDouble(tok[k], v[k]))
        throw std::runtime_error(where() + "field " + std::to_string(k + 1) + " '" +
                                 std::string(tok[k]) + "' is not a number");
      if (!std::isfinite(v[k]))
        throw std::runtime_error(where() + "field " + std::to_string(k + 1) + " is not finite");
    }
    TStampedPose p;
    p.timestamp = v[0];
    p.p_W_C = Vec3(v[1], v[2], v[3]);
    const Vec4 q(v[7], v[4], v[5], v[6]);  // file: qx qy qz qw -> ours: qw qx qy qz
    const double n = q.stableNorm();  // no overflow for components near DBL_MAX (fuzz: tests/fuzz/regressions/dataset)
    if (!(n > 1e-12)) throw std::runtime_error(where() + "zero quaternion");
    p.q_W_C = q / n;
    traj.push_back(p);
  }
  if (f.bad()) throw std::runtime_error(path + ": read error");
  return traj;
}

std::string formatTumLine(const TStampedPose& p)
{
  std::string s;
  s.reserve(160);
  std::array<char, 64> buf{};
  const auto res = std::to_chars(buf.data(), buf.data() + buf.size(), p.timestamp,
                                 std::chars_format::fixed, 6);
  s.append(buf.data(), res.ptr);
  const double vals[7] = {p.p_W_C.x(), p.p_W_C.y(), p.p_W_C.z(), p.q_W_C[1],
                          p.q_W_C[2],  p.q_W_C[3],  p.q_W_C[0]};
  for (double v : vals)
  {
    s.push_back(' ');
    appendShortest(s, v);
  }
  return s;
}

void writeTumTrajectory(const TTrajectory& traj, const std::string& path)
{
  std::ofstream f(path);
  if (!f) throw std::runtime_error(path + ": cannot open for writing");
  for (const auto& p : traj) f << formatTumLine(p) << '\n';
  f.flush();
  if (!f) throw std::runtime_error(path + ": write error");
}

std::vector<Vec3> trajectoryPositions(const TTrajectory& traj)
{
  std::vector<Vec3> out;
  out.reserve(traj.size());
  for (const auto& p : traj) out.push_back(p.p_W_C);
  return out;
}
}  // namespace immslam::core
