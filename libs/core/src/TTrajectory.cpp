/* imm-monoslam — TUM trajectory files. */
#include <immslam/core/TTrajectory.h>
#include <immslam/math/quaternion.h>

#include <algorithm>
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
TStampedPose interpolatePose(const TStampedPose& a, const TStampedPose& b, double t)
{
  const double span = b.timestamp - a.timestamp;
  const double u = span > 0 ? std::clamp((t - a.timestamp) / span, 0.0, 1.0) : 0.0;
  TStampedPose out;
  out.timestamp = t;
  out.p_W_C = (1 - u) * a.p_W_C + u * b.p_W_C;
  out.q_W_C = math::fromEigen(math::toEigen(a.q_W_C).slerp(u, math::toEigen(b.q_W_C)).normalized());
  return out;
}

TStampedPose carryPose(const TStampedPose& to, const TStampedPose& from, const TStampedPose& p)
{
  // from^-1 p: p in the camera frame of `from`; then to * that.
  const Vec4 qFromInv = math::quatConjugate(from.q_W_C);
  const Vec3 pRel = math::quatRotate(qFromInv, p.p_W_C - from.p_W_C);
  const Vec4 qRel = math::quatNormalized(math::quatMultiply(qFromInv, p.q_W_C));
  TStampedPose out;
  out.timestamp = p.timestamp;
  out.p_W_C = to.p_W_C + math::quatRotate(to.q_W_C, pRel);
  out.q_W_C = math::quatNormalized(math::quatMultiply(to.q_W_C, qRel));
  return out;
}

TTrajectory completeTrajectory(const TTrajectory& placed, const TTrajectory& all)
{
  // Each placed pose's index in `all` (both in time order: one merge); a placed pose at no time of
  // `all` is left out.
  constexpr double kSameTime = 1e-6;
  std::vector<std::size_t> at(all.size(), placed.size());  // per frame of `all`: its placed pose, if any
  std::vector<std::size_t> placedFrames;                    // the frames of `all` that have one
  for (std::size_t i = 0, k = 0; i < all.size() && k < placed.size();)
  {
    const double d = placed[k].timestamp - all[i].timestamp;
    if (std::abs(d) <= kSameTime)
    {
      at[i] = k++;
      placedFrames.push_back(i++);
    }
    else if (d < 0)
      ++k;
    else
      ++i;
  }
  if (placedFrames.empty()) return all;
  TTrajectory out;
  out.reserve(all.size());
  std::size_t next = 0;  // placed frames before i (placedFrames[next] is the first one after it)
  for (std::size_t i = 0; i < all.size(); ++i)
  {
    if (at[i] < placed.size())
    {
      out.push_back(placed[at[i]]);
      ++next;
    }
    else if (next == 0)
      out.push_back(carryPose(placed[at[placedFrames[0]]], all[placedFrames[0]], all[i]));
    else if (next == placedFrames.size())
      out.push_back(carryPose(placed[at[placedFrames.back()]], all[placedFrames.back()], all[i]));
    else
      out.push_back(interpolatePose(placed[at[placedFrames[next - 1]]], placed[at[placedFrames[next]]], all[i].timestamp));
  }
  return out;
}

}  // namespace immslam::core
