// The AVX-512 "vector ops" of the kernels written once over a vector type
// (nn/dwconv_block.h, nn/layernorm_rows.h): 16 floats per zmm, one intrinsic per
// operation. Include only from *_avx512.cpp files (compiled with AVX-512 flags). The same
// interface as nn/arch/x86/vecops_avx2.h and nn/arch/arm/vecops_neon.h.
#pragma once

#include <immintrin.h>

// GCC 12's AVX-512 headers build masked intrinsics on a self-initialised "undefined"
// vector, which -Wmaybe-uninitialized reports at every inlined use (GCC PR 105593). The
// uses are inlined into the including file's templates, so the warning is off for it.
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

namespace nn {
namespace {

struct VecOpsAvx512 {
  using V = __m512;
  using Mask = __mmask16;  // lanes [0, n)
  using V4 = __m128;  // one float per row of a group of four; GCC vector operators apply
  static constexpr int kLanes = 16;

  static V zero() { return _mm512_setzero_ps(); }
  static V set1(float x) { return _mm512_set1_ps(x); }
  static V load(const float* p) { return _mm512_load_ps(p); }  // 64-byte aligned
  static V loadu(const float* p) { return _mm512_loadu_ps(p); }
  static V broadcast(const float* p) { return _mm512_set1_ps(*p); }  // *p in every lane
  static void store(float* p, V v) { _mm512_store_ps(p, v); }  // 64-byte aligned
  static void storeu(float* p, V v) { _mm512_storeu_ps(p, v); }
  static Mask mask(int n) { return static_cast<__mmask16>((1u << n) - 1u); }
  // Lanes outside the mask: not read, loaded as zero; not written.
  static V load_part(const float* p, Mask m) { return _mm512_maskz_loadu_ps(m, p); }
  static void store_part(float* p, Mask m, V v) { _mm512_mask_storeu_ps(p, m, v); }
  static V keep(Mask m, V v) { return _mm512_maskz_mov_ps(m, v); }
  static V add(V a, V b) { return _mm512_add_ps(a, b); }
  static V sub(V a, V b) { return _mm512_sub_ps(a, b); }
  static V mul(V a, V b) { return _mm512_mul_ps(a, b); }
  static V div(V a, V b) { return _mm512_div_ps(a, b); }
  static V fma(V a, V b, V c) { return _mm512_fmadd_ps(a, b, c); }  // a * b + c, one rounding
  static V fnma(V a, V b, V c) { return _mm512_fnmadd_ps(a, b, c); }  // c - a * b, one rounding
  // To the nearest integer, ties to even.
  static V round_nearest(V a) {
    return _mm512_roundscale_ps(a, _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC);
  }
  // a never NaN: maxps/minps return their second operand on NaN, so NaN in b propagates
  // as in torch.
  static V max(V a, V b) { return _mm512_max_ps(a, b); }
  static V min(V a, V b) { return _mm512_min_ps(a, b); }

  static V4 sqrt4(V4 v) { return _mm_sqrt_ps(v); }
  static V4 max4(V4 a, V4 b) { return _mm_max_ps(a, b); }  // b on NaN

  // Lane k = sum of the lanes of the k-th vector, folded by halves (lane i + lane i + half):
  // 512 -> 256 -> 128 -> 64 -> 32 bits; the four folds share the shuffles.
  static V4 fold4(V a, V b, V c, V d) {
    const __m512 ab = _mm512_add_ps(_mm512_shuffle_f32x4(a, b, _MM_SHUFFLE(1, 0, 1, 0)),
                                    _mm512_shuffle_f32x4(a, b, _MM_SHUFFLE(3, 2, 3, 2)));
    const __m512 cd = _mm512_add_ps(_mm512_shuffle_f32x4(c, d, _MM_SHUFFLE(1, 0, 1, 0)),
                                    _mm512_shuffle_f32x4(c, d, _MM_SHUFFLE(3, 2, 3, 2)));
    // 128-bit lane k now holds row k's 4-float partial: [a, b, c, d].
    const __m512 s = _mm512_add_ps(_mm512_shuffle_f32x4(ab, cd, _MM_SHUFFLE(2, 0, 2, 0)),
                                   _mm512_shuffle_f32x4(ab, cd, _MM_SHUFFLE(3, 1, 3, 1)));
    const __m512 t = _mm512_add_ps(s, _mm512_permute_ps(s, _MM_SHUFFLE(1, 0, 3, 2)));
    const __m512 u = _mm512_add_ps(t, _mm512_permute_ps(t, _MM_SHUFFLE(2, 3, 0, 1)));
    const __m512i first = _mm512_setr_epi32(0, 4, 8, 12, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0);
    return _mm512_castps512_ps128(_mm512_permutexvar_ps(first, u));
  }
};

}  // namespace
}  // namespace nn
