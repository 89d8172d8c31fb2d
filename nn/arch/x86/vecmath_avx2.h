// AVX2+FMA element-wise math shared by the activation and GEMM-epilogue kernels, so both
// produce the same bits. Include only from *_avx2.cpp files (compiled with AVX2 flags).
// Same definitions and accuracy as nn/arch/x86/vecmath_avx512.h; the GELU table has 8 intervals
// (one vpermps reaches 8 entries), hence a degree-6 polynomial.
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

// h(a) = Phi(-a) on [0, 6): 8 intervals of width 3/4, a degree-6 polynomial in
// u = a * 4/3 - 0.5 - i per interval i (weighted GELU error a * |dh| <= 1.6e-8).
alignas(32) constexpr float kGeluTable8[7][8] = {
    {0.353830218f, 0.130294532f, 0.0303963646f, 0.00433244929f, 0.000369078683f,
     1.85367535e-05f, 5.44038755e-07f, 9.27496302e-09f},
    {-0.278891265f, -0.158907637f, -0.0515897088f, -0.00954308826f, -0.0010058406f,
     -6.04102061e-05f, -2.06773188e-06f, -4.0346201e-08f},
    {0.0392201766f, 0.0670387f, 0.036274083f, 0.00939403474f, 0.00127300539f,
     9.34398486e-05f, 3.77916899e-06f, 8.50568966e-08f},
    {0.022466151f, -0.00395167386f, -0.012166841f, -0.00527177891f, -0.000979768345f,
     -9.05413181e-05f, -4.38679581e-06f, -1.14271984e-07f},
    {-0.00526561122f, -0.00544611132f, 0.00087547343f, 0.00171325111f, 0.000500864408f,
     6.13693774e-05f, 3.66778431e-06f, 1.13190168e-07f},
    {-0.00156722416f, 0.00120694831f, 0.000779021415f, -0.00021681338f, -0.000171171647f,
     -3.15746765e-05f, -2.51333267e-06f, -9.82732615e-08f},
    {0.000481751194f, 0.000221013193f, -0.000240751688f, -5.43378774e-05f, 3.35252989e-05f,
     1.12106572e-05f, 1.20260199e-06f, 5.78770916e-08f},
};

// gelu(x) = x * Phi(x); see v512_gelu.
inline __m256 v256_gelu(__m256 x) {
  const __m256 a = _mm256_andnot_ps(_mm256_set1_ps(-0.0f), x);
  __m256 t = _mm256_fmadd_ps(a, _mm256_set1_ps(8.0f / 6.0f), _mm256_set1_ps(-0.5f));
  t = _mm256_min_ps(t, _mm256_set1_ps(7.49999952f));
  const __m256 magic = _mm256_set1_ps(12582912.0f);
  const __m256 rounded = _mm256_add_ps(t, magic);
  const __m256i idx = _mm256_castps_si256(rounded);
  const __m256 u = _mm256_sub_ps(t, _mm256_sub_ps(rounded, magic));
  __m256 h = _mm256_permutevar8x32_ps(_mm256_load_ps(kGeluTable8[6]), idx);
  for (int j = 5; j >= 0; --j)
    h = _mm256_fmadd_ps(h, u, _mm256_permutevar8x32_ps(_mm256_load_ps(kGeluTable8[j]), idx));
  h = _mm256_and_ps(h, _mm256_cmp_ps(a, _mm256_set1_ps(6.0f), _CMP_LT_OQ));
  const __m256 one_minus_h = _mm256_sub_ps(_mm256_set1_ps(1.0f), h);
  // blendv picks h where the sign bit of x is set: Phi(x) = h(|x|) for x < 0.
  const __m256 phi = _mm256_blendv_ps(one_minus_h, h, x);
  return _mm256_mul_ps(x, phi);
}

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
  static V gelu(V x) { return v256_gelu(x); }
  // max with the input as second operand: NaN propagates, as in PyTorch.
  static V relu(V x) { return max(zero(), x); }
  template <Act ACT>
  static V act(V x) { return vec_act<MathOpsAvx2, ACT>(x); }
};

}  // namespace
}  // namespace nn
