// The FMA-throughput loop behind nn::peak_gflops() (nn/peak.h, nn/peak_kernel.h), written
// once: kChains independent accumulators of the ISA's vector type V (a GCC vector of floats),
// each updated by Ops::step (one FMA; the scalar path's multiply and add) in every round,
// registers only. Every loop over acc[] is unrolled: GCC keeps an array in registers only
// when all its indices are constants. In an anonymous namespace: each ISA file compiles its
// own copy with its own flags.
#pragma once

namespace nn {
namespace {

template <class V, int kChains, class Ops>
double peak_loop_with(long iterations, float* sink) {
  constexpr int kLanes = sizeof(V) / sizeof(float);
  V acc[kChains];
#pragma GCC unroll 32
  for (int i = 0; i < kChains; ++i) acc[i] = V{} + static_cast<float>(i) * 1e-3f;
  // A factor just below 1 and a small addend: values stay finite and normal.
  const V mul = V{} + 0.999999f, add = V{} + 1e-6f;
  for (long it = 0; it < iterations; ++it) {
#pragma GCC unroll 32
    for (int i = 0; i < kChains; ++i) acc[i] = Ops::step(acc[i], mul, add);
  }
  V s = acc[0];
#pragma GCC unroll 32
  for (int i = 1; i < kChains; ++i) s = s + acc[i];
  float total = 0.0f;
  for (int l = 0; l < kLanes; ++l) total += s[l];
  *sink += total;  // the result is used, so the loop stays
  return static_cast<double>(iterations) * kChains * kLanes * 2;
}

}  // namespace
}  // namespace nn
