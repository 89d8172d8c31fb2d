// The AVX2 FMA-throughput loop (nn/peak_loop.h): 12 ymm chains, FMA latency x FMA ports on
// current cores.
#include <immintrin.h>

#include "nn/peak_kernel.h"
#include "nn/peak_loop.h"

namespace nn {
namespace {
struct FmaAvx2 {
  static __m256 step(__m256 acc, __m256 mul, __m256 add) { return _mm256_fmadd_ps(acc, mul, add); }
};
}  // namespace

double peak_fma_avx2(long iterations, float* sink) { return peak_loop_with<__m256, 12, FmaAvx2>(iterations, sink); }

}  // namespace nn
