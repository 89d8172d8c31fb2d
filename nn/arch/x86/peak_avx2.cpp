// The AVX2 FMA-throughput loop behind nn::peak_gflops() (nn/peak.h): 12 independent ymm accumulators
// (FMA latency x FMA ports on current cores), registers only.
#include <immintrin.h>

#include "nn/peak_kernel.h"

namespace nn {

double peak_fma_avx2(long iterations, float* sink) {
  __m256 acc[12];
#pragma GCC unroll 12
  for (int i = 0; i < 12; ++i) acc[i] = _mm256_set1_ps(static_cast<float>(i) * 1e-3f);
  const __m256 mul = _mm256_set1_ps(0.999999f), add = _mm256_set1_ps(1e-6f);
  for (long it = 0; it < iterations; ++it) {
#pragma GCC unroll 12
    for (int i = 0; i < 12; ++i) acc[i] = _mm256_fmadd_ps(acc[i], mul, add);
  }
  __m256 s = acc[0];
  for (int i = 1; i < 12; ++i) s = _mm256_add_ps(s, acc[i]);
  alignas(32) float lanes[8];
  _mm256_store_ps(lanes, s);
  for (float v : lanes) *sink += v;
  return static_cast<double>(iterations) * 12 * 8 * 2;
}

}  // namespace nn
