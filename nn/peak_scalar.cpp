// What the scalar path can reach: the baseline vector unit (SSE2 on x86-64, Advanced
// SIMD on aarch64) doing a multiply and an add per lane (no FMA: the scalar kernels do
// not contract), 12 independent chains of 4 lanes.
#include "nn/peak_kernel.h"

namespace nn {
namespace {
typedef float Vec4 __attribute__((vector_size(16)));
}  // namespace

double peak_fma_scalar(long iterations, float* sink) {
  Vec4 acc[12];
#pragma GCC unroll 12
  for (int i = 0; i < 12; ++i) acc[i] = Vec4{} + static_cast<float>(i) * 1e-3f;
  const Vec4 mul = Vec4{} + 0.999999f, add = Vec4{} + 1e-6f;
  for (long it = 0; it < iterations; ++it) {
#pragma GCC unroll 12
    for (int i = 0; i < 12; ++i) acc[i] = acc[i] * mul + add;
  }
  Vec4 s = acc[0];
  for (int i = 1; i < 12; ++i) s = s + acc[i];
  for (int l = 0; l < 4; ++l) *sink += s[l];
  return static_cast<double>(iterations) * 12 * 4 * 2;
}

}  // namespace nn
