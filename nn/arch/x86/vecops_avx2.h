// The AVX2+FMA "vector ops" of the kernels written once over a vector type
// (nn/dwconv_block.h, nn/layernorm_rows.h, nn/resize_row.h): 8 floats per ymm, one
// intrinsic per operation. Include only from *_avx2.cpp files (compiled with AVX2 flags).
// The same interface as nn/arch/x86/vecops_avx512.h and nn/arch/arm/vecops_neon.h.
#pragma once

#include <immintrin.h>

namespace nn {
namespace {

struct VecOpsAvx2 {
  using V = __m256;
  using Mask = __m256i;  // lanes [0, n) all ones
  using V4 = __m128;  // one float per row of a group of four; GCC vector operators apply
  static constexpr int kLanes = 8;

  static V zero() { return _mm256_setzero_ps(); }
  static V set1(float x) { return _mm256_set1_ps(x); }
  static V load(const float* p) { return _mm256_load_ps(p); }  // 32-byte aligned
  static V loadu(const float* p) { return _mm256_loadu_ps(p); }
  static V broadcast(const float* p) { return _mm256_broadcast_ss(p); }  // *p in every lane
  static void store(float* p, V v) { _mm256_store_ps(p, v); }  // 32-byte aligned
  static void storeu(float* p, V v) { _mm256_storeu_ps(p, v); }
  static Mask mask(int n) {
    return _mm256_cmpgt_epi32(_mm256_set1_epi32(n), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
  }
  // Lanes outside the mask: not read, loaded as zero; not written.
  static V load_part(const float* p, Mask m) { return _mm256_maskload_ps(p, m); }
  static void store_part(float* p, Mask m, V v) { _mm256_maskstore_ps(p, m, v); }
  static V keep(Mask m, V v) { return _mm256_and_ps(_mm256_castsi256_ps(m), v); }
  static V add(V a, V b) { return _mm256_add_ps(a, b); }
  static V sub(V a, V b) { return _mm256_sub_ps(a, b); }
  static V mul(V a, V b) { return _mm256_mul_ps(a, b); }
  static V div(V a, V b) { return _mm256_div_ps(a, b); }
  static V fma(V a, V b, V c) { return _mm256_fmadd_ps(a, b, c); }  // a * b + c, one rounding
  static V fnma(V a, V b, V c) { return _mm256_fnmadd_ps(a, b, c); }  // c - a * b, one rounding
  // To the nearest integer, ties to even.
  static V round_nearest(V a) {
    return _mm256_round_ps(a, _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC);
  }
  // a never NaN: maxps/minps return their second operand on NaN, so NaN in b propagates
  // as in torch.
  static V max(V a, V b) { return _mm256_max_ps(a, b); }
  static V min(V a, V b) { return _mm256_min_ps(a, b); }

  static V4 sqrt4(V4 v) { return _mm_sqrt_ps(v); }
  static V4 max4(V4 a, V4 b) { return _mm_max_ps(a, b); }  // b on NaN

  // Lane k = sum of the lanes of the k-th vector, folded by halves (lane i + lane i + half):
  // 256 -> 128 -> 64 -> 32 bits.
  static V4 fold4(V a, V b, V c, V d) {
    const __m256 ab =
        _mm256_add_ps(_mm256_permute2f128_ps(a, b, 0x20), _mm256_permute2f128_ps(a, b, 0x31));
    const __m256 cd =
        _mm256_add_ps(_mm256_permute2f128_ps(c, d, 0x20), _mm256_permute2f128_ps(c, d, 0x31));
    // Lanes: [a0+a2, a1+a3, c0+c2, c1+c3 | b0+b2, b1+b3, d0+d2, d1+d3].
    const __m256 s = _mm256_add_ps(_mm256_shuffle_ps(ab, cd, _MM_SHUFFLE(1, 0, 1, 0)),
                                   _mm256_shuffle_ps(ab, cd, _MM_SHUFFLE(3, 2, 3, 2)));
    // Lanes: [a, c, a, c | b, d, b, d].
    const __m256 t = _mm256_add_ps(_mm256_shuffle_ps(s, s, _MM_SHUFFLE(2, 0, 2, 0)),
                                   _mm256_shuffle_ps(s, s, _MM_SHUFFLE(3, 1, 3, 1)));
    return _mm_unpacklo_ps(_mm256_castps256_ps128(t), _mm256_extractf128_ps(t, 1));
  }
};

}  // namespace
}  // namespace nn
