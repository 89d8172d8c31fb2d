// The AVX-512 FMA-throughput loop (nn/peak_loop.h): 24 zmm chains, more than FMA latency x
// FMA ports on current cores.
#include <immintrin.h>

#include "nn/peak_kernel.h"
#include "nn/peak_loop.h"

namespace nn {
namespace {
struct FmaAvx512 {
  static __m512 step(__m512 acc, __m512 mul, __m512 add) { return _mm512_fmadd_ps(acc, mul, add); }
};
}  // namespace

double peak_fma_avx512(long iterations, float* sink) { return peak_loop_with<__m512, 24, FmaAvx512>(iterations, sink); }

}  // namespace nn
