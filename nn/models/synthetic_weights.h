// Seeded random weights for any model's tensor list, so demos, benchmarks and
// users can run every model without a trained checkpoint. The scales make every
// layer matter (as in the PyTorch comparison tests): conv/linear N(0, 1/fan_in),
// layer scale U(0.3, 1), norm gamma N(1, 0.2), norm beta N(0, 0.1), biases N(0, 0.05).
// Deterministic on every platform (own generator, not <random>'s distributions).
#pragma once

#include <cstdint>
#include <vector>

#include "weights/safetensors.h"
#include "weights/tensor_spec.h"

namespace nn {

class SplitMix64 {
 public:
  explicit SplitMix64(std::uint64_t seed) : s_(seed * 0x9E3779B97F4A7C15ull + 0x632BE59BD9B4E019ull) {}
  std::uint64_t next();
  double uniform();  // [0, 1)
  double normal();   // N(0, 1), Box-Muller

 private:
  std::uint64_t s_;
};

// Values for one tensor of `specs` following the scale rules above.
std::vector<float> synthetic_tensor(const weights::TensorSpec& spec,
                                    const std::vector<weights::TensorSpec>& specs, SplitMix64& rng);

// A safetensors file (in memory) holding every tensor of `specs`.
weights::Writer synthetic_weights(const std::vector<weights::TensorSpec>& specs, std::uint64_t seed);

}  // namespace nn
