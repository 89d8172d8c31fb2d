// The NEON FMA-throughput loop behind nn::peak_gflops() (nn/peak.h), registers only.
// 12 independent q-register chains: a Cortex-A76 / Neoverse-N1-class core has 2 FMA pipes
// with 4-cycle latency, so at least 8 chains are needed to keep both busy; 12 leaves
// headroom for wider cores (Neoverse V1/V2: 4 pipes) without spilling (12 + 2 of 32).
#include <arm_neon.h>

#include "nn/peak_kernel.h"

namespace nn {

double peak_fma_neon(long iterations, float* sink) {
  constexpr int kChains = 12;
  float32x4_t acc[kChains];
#pragma GCC unroll 12
  for (int i = 0; i < kChains; ++i) acc[i] = vdupq_n_f32(static_cast<float>(i) * 1e-3f);
  // acc += mul * add: the accumulator is fmla's destination, so no register copies.
  const float32x4_t mul = vdupq_n_f32(0.999999f), add = vdupq_n_f32(1e-6f);
  for (long it = 0; it < iterations; ++it) {
#pragma GCC unroll 12
    for (int i = 0; i < kChains; ++i) acc[i] = vfmaq_f32(acc[i], mul, add);
  }
  // Unrolled like the loops above: an indexed loop here would keep acc[] in memory and
  // store all 12 vectors in every iteration.
  float32x4_t s = acc[0];
#pragma GCC unroll 12
  for (int i = 1; i < kChains; ++i) s = vaddq_f32(s, acc[i]);
  *sink += vaddvq_f32(s);
  return static_cast<double>(iterations) * kChains * 4 * 2;
}

}  // namespace nn
