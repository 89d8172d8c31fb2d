// Seeded uniform test data shared by the kernel tests.
#pragma once

#include <cstddef>
#include <random>
#include <vector>

namespace nntest {

// n floats uniform in [lo, hi), the same for the same seed on every run.
inline std::vector<float> random_vector(std::size_t n, unsigned seed, float lo = -1.0f, float hi = 1.0f) {
  std::mt19937 gen(seed);
  std::uniform_real_distribution<float> dist(lo, hi);
  std::vector<float> v(n);
  for (auto& x : v) x = dist(gen);
  return v;
}

// n floats uniform in [-scale, scale).
inline std::vector<float> random_symmetric(std::size_t n, unsigned seed, float scale = 1.0f) {
  return random_vector(n, seed, -scale, scale);
}

}  // namespace nntest
