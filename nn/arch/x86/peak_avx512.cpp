// The AVX-512 FMA-throughput loop behind nn::peak_gflops() (nn/peak.h): 24 independent zmm accumulators
// (more than FMA latency x FMA ports on current cores), registers only.
#include <immintrin.h>

#include "nn/peak_kernel.h"

namespace nn {

// Runs `iterations` rounds of 24 FMAs on 16 lanes; returns the flops performed. Strict FP
// semantics keep every FMA, and the result goes to *sink so the loop is not removed.
double peak_fma_avx512(long iterations, float* sink) {
  __m512 acc[24];
#pragma GCC unroll 24
  for (int i = 0; i < 24; ++i) acc[i] = _mm512_set1_ps(static_cast<float>(i) * 1e-3f);
  // Multiplier just below 1 and a small addend: values stay finite and normal.
  const __m512 mul = _mm512_set1_ps(0.999999f), add = _mm512_set1_ps(1e-6f);
  for (long it = 0; it < iterations; ++it) {
#pragma GCC unroll 24
    for (int i = 0; i < 24; ++i) acc[i] = _mm512_fmadd_ps(acc[i], mul, add);
  }
  __m512 s = acc[0];
  for (int i = 1; i < 24; ++i) s = _mm512_add_ps(s, acc[i]);
  alignas(64) float lanes[16];
  _mm512_store_ps(lanes, s);
  for (float v : lanes) *sink += v;
  return static_cast<double>(iterations) * 24 * 16 * 2;
}

}  // namespace nn
