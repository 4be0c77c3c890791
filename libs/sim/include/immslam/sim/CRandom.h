/* imm-monoslam — platform-independent deterministic random numbers for the renderer. */
#pragma once

#include <cstdint>
#include <string_view>

namespace immslam::sim
{
/** A small deterministic generator (xoshiro256** seeded through SplitMix64) with its own
 * uniform and normal conversions, so a scenario renders the same bytes with any standard library
 * (the distributions of <random> are implementation-defined).
 *
 * Independent streams are derived from one seed with streamSeed(): the camera path, the world,
 * each moving object and the pixel noise each have their own, so enabling moving objects never
 * changes the camera path or the static world. */
class CRandom
{
 public:
  explicit CRandom(std::uint64_t seed);

  /** Next raw 64-bit value. */
  std::uint64_t next();

  /** Uniform in [0, 1) with 53 random bits. */
  double uniform();

  /** Uniform in [a, b). */
  double uniform(double a, double b) { return a + (b - a) * uniform(); }

  /** Log-uniform in [a, b) (0 < a <= b): scales spread evenly over octaves. */
  double logUniform(double a, double b);

  /** Uniform integer in [lo, hi] (inclusive). */
  int uniformInt(int lo, int hi);

  /** Standard normal (Box-Muller; the second value of each pair is kept for the next call). */
  double normal();

  /** A seed for the stream called `name` (and optional indices) of the master `seed`. */
  static std::uint64_t streamSeed(std::uint64_t seed, std::string_view name, std::uint64_t i = 0,
                                  std::uint64_t j = 0);

  /** The SplitMix64 finalizer: a bijective 64-bit mix. */
  static std::uint64_t mix(std::uint64_t x);

 private:
  std::uint64_t m_s[4];
  double m_spare = 0;
  bool m_hasSpare = false;
};
}  // namespace immslam::sim
