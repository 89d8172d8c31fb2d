// AVX2+FMA element-wise math shared by the activation and GEMM-epilogue kernels, so both
// produce the same bits. Include only from *_avx2.cpp files (compiled with AVX2 flags).
// Same definitions and accuracy as nn/arch/x86/vecmath_avx512.h; the GELU is the 8-interval
// one of nn/vecmath_act.h (one vpermps reaches 8 entries), shared with NEON.
#pragma once

// GCC 12 reports the _mm512_undefined_ps() inside its own intrinsics as "may be used
// uninitialized" once they are inlined (GCC PR 105593, fixed in 13); the warning is
// located in the intrinsic headers, so it is silenced for them only.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <immintrin.h>
#pragma GCC diagnostic pop

#include "nn/act.h"
#include "nn/arch/x86/vecops_avx2.h"
#include "nn/vecmath_act.h"

namespace nn {
namespace {

// The AVX2 vector ops with this file's GELU, ReLU and exp steps: the trait of the kernels
// written once over a vector type that apply an activation (nn/vecmath_act.h builds the
// others from these; nn/activation_loop.h, nn/gemm_tile_frame.h).
struct MathOpsAvx2 : VecOpsAvx2 {
  // exp (nn/vecmath_act.h): 2^n built in the exponent field. n clamped to [-127, 128]
  // gives the bit patterns of 0 and inf at the ends (underflow to zero, overflow to
  // infinity).
  static constexpr float kExpClamp = 100.0f;
  static V times_pow2(V p, V n) {
    const __m256 nc = min(max(n, set1(-127.0f)), set1(128.0f));
    const __m256i bits =
        _mm256_slli_epi32(_mm256_add_epi32(_mm256_cvtps_epi32(nc), _mm256_set1_epi32(127)), 23);
    return mul(p, _mm256_castsi256_ps(bits));
  }
  // The GELU of nn/vecmath_act.h from the 8-interval table: vpermps reads the interval
  // index from the low three bits of each lane of t + 1.5 * 2^23.
  using Table8Index = __m256i;
  static Table8Index table8_index(V rounded) { return _mm256_castps_si256(rounded); }
  static V table8_lookup(const float* row, Table8Index i) {
    return _mm256_permutevar8x32_ps(_mm256_load_ps(row), i);
  }
  static V abs(V a) { return _mm256_andnot_ps(_mm256_set1_ps(-0.0f), a); }
  static V keep_if_less(V v, V a, V b) { return _mm256_and_ps(v, _mm256_cmp_ps(a, b, _CMP_LT_OQ)); }
  static V select_negative(V x, V if_neg, V otherwise) { return _mm256_blendv_ps(otherwise, if_neg, x); }
  static V gelu(V x) { return vec_gelu_table8<MathOpsAvx2>(x); }
  // max with the input as second operand: NaN propagates, as in PyTorch.
  static V relu(V x) { return max(zero(), x); }
  template <Act ACT>
  static V act(V x) { return vec_act<MathOpsAvx2, ACT>(x); }
};

}  // namespace
}  // namespace nn
