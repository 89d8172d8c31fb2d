#include "nn/models/synthetic_weights.h"

#include <cmath>
#include <string>

namespace nn {

namespace {

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// A 1-D ".bias" whose ".weight" is also 1-D belongs to a normalisation layer (beta).
bool is_norm_bias(const weights::TensorSpec& spec, const std::vector<weights::TensorSpec>& all) {
  if (spec.shape.size() != 1 || !ends_with(spec.name, ".bias")) return false;
  const std::string weight = spec.name.substr(0, spec.name.size() - 5) + ".weight";
  for (const auto& s : all)
    if (s.name == weight) return s.shape.size() == 1;
  return false;
}

}  // namespace

std::uint64_t SplitMix64::next() {
  std::uint64_t z = (s_ += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

double SplitMix64::uniform() { return (next() >> 11) * (1.0 / 9007199254740992.0); }

double SplitMix64::normal() {
  const double u1 = 1.0 - uniform(), u2 = uniform();
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
}

std::vector<float> synthetic_tensor(const weights::TensorSpec& spec,
                                    const std::vector<weights::TensorSpec>& specs, SplitMix64& rng) {
  std::int64_t n = 1;
  for (auto d : spec.shape) n *= d;
  std::vector<float> v(static_cast<std::size_t>(n));
  const bool vector = spec.shape.size() == 1;
  const bool norm_bias = is_norm_bias(spec, specs);
  const double fan_in = spec.shape.empty() || spec.shape[0] == 0 ? 1.0 : static_cast<double>(n / spec.shape[0]);
  for (auto& x : v) {
    if (ends_with(spec.name, "layer_scale"))
      x = static_cast<float>(0.3 + 0.7 * rng.uniform());
    else if (norm_bias)
      x = static_cast<float>(0.1 * rng.normal());
    else if (vector && ends_with(spec.name, ".bias"))
      x = static_cast<float>(0.05 * rng.normal());
    else if (vector)  // a norm's gamma
      x = static_cast<float>(1.0 + 0.2 * rng.normal());
    else
      x = static_cast<float>(rng.normal() / std::sqrt(fan_in));
  }
  return v;
}

weights::Writer synthetic_weights(const std::vector<weights::TensorSpec>& specs, std::uint64_t seed) {
  SplitMix64 rng(seed);
  weights::Writer w;
  w.set_metadata("format", "roadnn-v1");
  w.set_metadata("generator", "synthetic seed " + std::to_string(seed) + " (random, untrained)");
  for (const auto& spec : specs) {
    auto v = synthetic_tensor(spec, specs, rng);
    w.add_f32(spec.name, spec.shape, v.data());
  }
  return w;
}

}  // namespace nn
