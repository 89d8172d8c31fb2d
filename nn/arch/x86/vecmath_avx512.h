// AVX-512 element-wise math shared by the activation and GEMM-epilogue kernels, so both
// produce the same bits. Include only from *_avx512.cpp files (compiled with AVX-512 flags).
//
// Accuracy (checked by tests/nn/test_activation.cpp against double-precision definitions):
//   gelu: within 1e-6 absolute of x * Phi(x) everywhere (at most 1.9e-7 from the
//         approximation, the rest is float rounding); NaN in -> NaN out; gelu(-inf) = NaN,
//         like PyTorch.
//   exp / sigmoid (nn/vecmath_act.h, with the steps of MathOpsAvx512 below): about 1 ulp
//         relative / 1e-7 absolute.
#pragma once

// GCC 12 reports the _mm512_undefined_ps() inside its own intrinsics as "may be used
// uninitialized" once they are inlined (GCC PR 105593, fixed in 13); the warning is
// located in the intrinsic headers, so it is silenced for them only.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <immintrin.h>
#pragma GCC diagnostic pop

#include "nn/act.h"
#include "nn/arch/x86/vecops_avx512.h"
#include "nn/vecmath_act.h"

namespace nn {
namespace {

// h(a) = Phi(-a) = erfc(a / sqrt 2) / 2 on [0, 6): 32 intervals of width 3/16, a cubic in
// u = a * 16/3 - 0.5 - i (u in [-0.5, 0.5]) per interval i, fitted by weighted minimax of
// the GELU error a * |dh| (max 1.9e-7 with these float coefficients) in double against
// mpmath's erfc. Row j holds the u^j coefficients of all 32 intervals: one two-table
// permute fetches them for 16 lanes. (Zen 5 runs permutes and FMAs on the same two pipes,
// so a cubic over 32 intervals beats a quintic over 16: about 5.8 against 7.4 cycles.)
alignas(64) constexpr float kGeluTable32[4][32] = {
    {0.462653935f, 0.389259458f, 0.319624364f, 0.255831867f, 0.199404776f, 0.151211992f,
     0.111469693f, 0.0798250437f, 0.0554960594f, 0.0374358036f, 0.0244908668f,
     0.0155320214f, 0.00954542309f, 0.00568278553f, 0.00327640912f, 0.00182890857f,
     0.000988192856f, 0.000516721862f, 0.000261430716f, 0.000127958308f, 6.05797395e-05f,
     2.7737964e-05f, 1.22816573e-05f, 5.25807218e-06f, 2.17640491e-06f, 8.70876818e-07f,
     3.36853844e-07f, 1.25939195e-07f, 4.55076794e-08f, 1.58922386e-08f, 5.36335376e-09f,
     1.74910275e-09f},
    {-0.0744736791f, -0.0719007179f, -0.0670188591f, -0.0603104755f, -0.0523986444f,
     -0.0439521f, -0.035593532f, -0.027828794f, -0.0210062861f, -0.0153086241f,
     -0.01077097f, -0.00731653161f, -0.00479829684f, -0.00303809135f, -0.00185714569f,
     -0.00109603046f, -0.000624497479f, -0.00034353431f, -0.000182448741f, -9.35497883e-05f,
     -4.63101169e-05f, -2.21329865e-05f, -1.02125723e-05f, -4.54947303e-06f,
     -1.95667121e-06f, -8.12466169e-07f, -3.2570415e-07f, -1.26058382e-07f,
     -4.71032102e-08f, -1.69925869e-08f, -5.91832228e-09f, -1.99006678e-09f},
    {0.000652922899f, 0.00189177482f, 0.0029392296f, 0.00370356627f, 0.00413793465f,
     0.00424327748f, 0.00406234013f, 0.00366607029f, 0.00313757197f, 0.00255673332f,
     0.00198926707f, 0.00148080441f, 0.00105623365f, 0.000722748984f, 0.000474875502f,
     0.000299817359f, 0.000182001415f, 0.000106279542f, 5.97252074e-05f, 3.23109634e-05f,
     1.68326169e-05f, 8.44642364e-06f, 4.08326605e-06f, 1.90211949e-06f, 8.53954248e-07f,
     3.69539947e-07f, 1.54160588e-07f, 6.20041334e-08f, 2.4046237e-08f, 8.99274255e-09f,
     3.24333738e-09f, 1.12818022e-09f},
    {0.000432214874f, 0.000386363827f, 0.000304997724f, 0.000200250521f, 8.78183419e-05f,
     -1.65185884e-05f, -0.000101055637f, -0.000159031071f, -0.00018918069f,
     -0.000194555585f, -0.000181240423f, -0.00015628236f, -0.000126258281f,
     -9.62550985e-05f, -6.95943745e-05f, -4.78820548e-05f, -3.14270874e-05f,
     -1.97142217e-05f, -1.18366079e-05f, -6.81009396e-06f, -3.75800914e-06f,
     -1.99053511e-06f, -1.01266176e-06f, -4.95081736e-07f, -2.32701211e-07f,
     -1.05196293e-07f, -4.57538434e-08f, -1.91517522e-08f, -7.71708208e-09f,
     -2.99405789e-09f, -1.11870524e-09f, -4.02623851e-10f},
};

// gelu(x) = x * Phi(x), Phi(x) = 1 - h(|x|) for x >= 0 and h(|x|) below. Beyond |x| = 6,
// h < 1e-9 is taken as 0: gelu is x or -0 there (so gelu(-inf) = -inf * 0 = NaN).
inline __m512 v512_gelu(__m512 x) {
  const __m512 a = _mm512_abs_ps(x);
  __m512 t = _mm512_fmadd_ps(a, _mm512_set1_ps(32.0f / 6.0f), _mm512_set1_ps(-0.5f));
  t = _mm512_min_ps(t, _mm512_set1_ps(31.4999981f));
  // Adding 1.5 * 2^23 rounds t to the nearest integer i and leaves it in the low mantissa
  // bits, which is all the permutes read; reduce gives u = t - i with the same rounding.
  const __m512i idx = _mm512_castps_si512(_mm512_add_ps(t, _mm512_set1_ps(12582912.0f)));
  const __m512 u = _mm512_reduce_ps(t, _MM_FROUND_TO_NEAREST_INT);
  auto coef = [&](int j) {
    return _mm512_permutex2var_ps(_mm512_load_ps(kGeluTable32[j]), idx,
                                  _mm512_load_ps(kGeluTable32[j] + 16));
  };
  __m512 h = _mm512_fmadd_ps(coef(3), u, coef(2));
  h = _mm512_fmadd_ps(h, u, coef(1));
  const __mmask16 inside = _mm512_cmp_ps_mask(a, _mm512_set1_ps(6.0f), _CMP_LT_OQ);
  h = _mm512_maskz_fmadd_ps(inside, h, u, coef(0));
  const __mmask16 nonneg = _mm512_cmp_ps_mask(x, _mm512_setzero_ps(), _CMP_GE_OQ);
  const __m512 phi = _mm512_mask_sub_ps(h, nonneg, _mm512_set1_ps(1.0f), h);
  return _mm512_mul_ps(x, phi);
}

// The AVX-512 vector ops with this file's GELU, ReLU and exp steps: the trait of the kernels
// written once over a vector type that apply an activation (nn/vecmath_act.h builds the
// others from these; nn/activation_loop.h, nn/gemm_tile_frame.h).
struct MathOpsAvx512 : VecOpsAvx512 {
  // exp (nn/vecmath_act.h): scalef gives 2^n with overflow to inf and underflow to zero
  // for any n, so the clamp only keeps inf - inf out of the reduction.
  static constexpr float kExpClamp = 150.0f;
  static V times_pow2(V p, V n) { return _mm512_scalef_ps(p, n); }
  static V gelu(V x) { return v512_gelu(x); }
  // max with the input as second operand: NaN propagates, as in PyTorch.
  static V relu(V x) { return max(zero(), x); }
  template <Act ACT>
  static V act(V x) { return vec_act<MathOpsAvx512, ACT>(x); }
};

}  // namespace
}  // namespace nn
