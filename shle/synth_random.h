// Counter-based random numbers for the synthetic generator: every value is a hash
// of (seed, stream, indices), so any frame or pixel can be generated alone and the
// output never depends on the evaluation order or the standard library.
#pragma once

#include <cmath>
#include <cstdint>

namespace shle {
namespace synth {

inline std::uint64_t mix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

inline std::uint64_t hash(std::uint64_t a, std::uint64_t b = 0, std::uint64_t c = 0, std::uint64_t d = 0) {
  return mix64(mix64(mix64(mix64(a) ^ b) ^ c) ^ d);
}

// Uniform in [0, 1) with 53 random bits.
inline double unit(std::uint64_t h) { return static_cast<double>(h >> 11) * (1.0 / 9007199254740992.0); }

inline double uniform(double lo, double hi, std::uint64_t h) { return lo + (hi - lo) * unit(h); }

// Standard normal from one hash (Box-Muller on two derived uniforms).
inline double normal(std::uint64_t h) {
  double u1 = unit(mix64(h ^ 0x5851F42D4C957F2Dull)), u2 = unit(mix64(h + 0x14057B7EF767814Full));
  if (u1 < 1e-300) u1 = 1e-300;
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
}

// Sequential stream for scene construction.
class Stream {
 public:
  explicit Stream(std::uint64_t seed) : s_(seed) {}
  std::uint64_t next() { return mix64(s_++ * 0x2545F4914F6CDD1Dull + 0x632BE59BD9B4E019ull); }
  double unit() { return synth::unit(next()); }
  double uniform(double lo, double hi) { return lo + (hi - lo) * unit(); }
  double normal() { return synth::normal(next()); }

 private:
  std::uint64_t s_;
};

}  // namespace synth
}  // namespace shle
