/* imm-monoslam — deterministic random numbers (see CRandom.h). */
#include <immslam/sim/CRandom.h>

#include <cmath>

namespace immslam::sim
{
namespace
{
std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
}  // namespace

std::uint64_t CRandom::mix(std::uint64_t x)
{
  // SplitMix64 output function (Steele, Lea, Flood 2014).
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

std::uint64_t CRandom::streamSeed(std::uint64_t seed, std::string_view name, std::uint64_t i,
                                  std::uint64_t j)
{
  // FNV-1a of the name, then mixed with the seed and the indices.
  std::uint64_t h = 0xCBF29CE484222325ULL;
  for (const char c : name)
  {
    h ^= static_cast<unsigned char>(c);
    h *= 0x100000001B3ULL;
  }
  return mix(mix(mix(seed ^ mix(h)) + i) ^ mix(j + 0x51ED27ULL));
}

CRandom::CRandom(std::uint64_t seed)
{
  std::uint64_t x = seed;
  for (auto& s : m_s)
  {
    x = mix(x);
    s = x;
  }
}

std::uint64_t CRandom::next()
{
  // xoshiro256** (Blackman & Vigna).
  const std::uint64_t result = rotl(m_s[1] * 5, 7) * 9;
  const std::uint64_t t = m_s[1] << 17;
  m_s[2] ^= m_s[0];
  m_s[3] ^= m_s[1];
  m_s[1] ^= m_s[2];
  m_s[0] ^= m_s[3];
  m_s[2] ^= t;
  m_s[3] = rotl(m_s[3], 45);
  return result;
}

double CRandom::uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }

double CRandom::logUniform(double a, double b) { return a * std::exp(uniform() * std::log(b / a)); }

int CRandom::uniformInt(int lo, int hi)
{
  const std::uint64_t n = static_cast<std::uint64_t>(static_cast<std::int64_t>(hi) - lo + 1);
  return lo + static_cast<int>(next() % n);
}

double CRandom::normal()
{
  if (m_hasSpare)
  {
    m_hasSpare = false;
    return m_spare;
  }
  double u1 = uniform();
  while (u1 <= 0.0) u1 = uniform();
  const double u2 = uniform();
  const double r = std::sqrt(-2.0 * std::log(u1));
  const double a = 2.0 * M_PI * u2;
  m_spare = r * std::sin(a);
  m_hasSpare = true;
  return r * std::cos(a);
}
}  // namespace immslam::sim
