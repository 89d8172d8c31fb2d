// Seeded uniform data for the benchmarks' set-up: the same values on every run and
// build, so two figures of one benchmark time the same arithmetic (a GELU or a denormal
// costs what the values make it cost).
#pragma once

#include <cstddef>
#include <random>
#include <vector>

namespace nnbench {

// Floats uniform in [-1, 1) from one seeded generator. Successive calls continue the
// stream: a set-up that draws its tensors in a fixed order always gets the same values.
class UniformStream {
 public:
  explicit UniformStream(unsigned seed = 1) : gen_(seed) {}

  float next() { return dist_(gen_); }

  // n values offset + scale * u.
  std::vector<float> vector(std::size_t n, float scale = 1.0f, float offset = 0.0f) {
    std::vector<float> v(n);
    for (float& x : v) x = offset + scale * next();
    return v;
  }

 private:
  std::mt19937 gen_;
  std::uniform_real_distribution<float> dist_{-1.0f, 1.0f};
};

}  // namespace nnbench
