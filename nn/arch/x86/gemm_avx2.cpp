// AVX2+FMA GEMM micro-kernels: MR rows of A broadcast against NR/8 ymm columns of the
// packed W panel, MR x NR/8 accumulators in registers, one FMA per (row, vector, k).
// Row tails are separate instantiations (R < MR); column tails use maskload/maskstore in
// the store phase (the padded panel columns are zero, so the K loop needs no masking).
#include <cstddef>

#include "nn/gemm_kernels.h"
#include "nn/arch/x86/vecmath_avx2.h"

namespace nn {
namespace {

#define NN_UNROLL _Pragma("GCC unroll 16")

// Lane j is enabled when j < valid.
inline __m256i column_mask(int valid) {
  return _mm256_cmpgt_epi32(_mm256_set1_epi32(valid), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
}

// The epilogue of nn/gemm.h on R rows of raw sums (tile, row stride NR): bias, act, scale,
// residual (read just before the same element of C is written, so it may alias C), act.
// Out of line: with 16 ymm registers, GCC otherwise spills the K loop's accumulators
// inside the loop to make room for the epilogue.
template <Act ACT, int R, int NR>
__attribute__((noinline)) void store_epilogue(const float* tile, const GemmTile& t) {
  const GemmTileEpilogue& ep = *t.ep;
  for (int r = 0; r < R; ++r) {
    float* c = t.c + r * t.ldc;
    const float* res = ep.residual ? ep.residual + r * ep.ldr : nullptr;
    for (int v = 0; v * 8 < t.nr; ++v) {
      const int valid = t.nr - 8 * v;
      __m256 x = _mm256_load_ps(tile + r * NR + 8 * v);
      if (valid >= 8) {
        if (ep.bias) x = _mm256_add_ps(x, _mm256_loadu_ps(ep.bias + 8 * v));
        if (!ep.act_after_residual) x = v256_act<ACT>(x);
        if (ep.scale) x = _mm256_mul_ps(x, _mm256_loadu_ps(ep.scale + 8 * v));
        if (res) x = _mm256_add_ps(x, _mm256_loadu_ps(res + 8 * v));
        if (ep.act_after_residual) x = v256_act<ACT>(x);
        _mm256_storeu_ps(c + 8 * v, x);
      } else {
        const __m256i m = column_mask(valid);
        if (ep.bias) x = _mm256_add_ps(x, _mm256_maskload_ps(ep.bias + 8 * v, m));
        if (!ep.act_after_residual) x = v256_act<ACT>(x);
        if (ep.scale) x = _mm256_mul_ps(x, _mm256_maskload_ps(ep.scale + 8 * v, m));
        if (res) x = _mm256_add_ps(x, _mm256_maskload_ps(res + 8 * v, m));
        if (ep.act_after_residual) x = v256_act<ACT>(x);
        _mm256_maskstore_ps(c + 8 * v, m, x);
      }
    }
  }
}

template <int R, int NV>
void tile_kernel(const GemmTile& t) {
  constexpr int NR = 8 * NV;
  // Every loop over acc is unrolled completely (NN_UNROLL): GCC keeps acc[][] in registers
  // only when all its indices are constants.
  __m256 acc[R][NV];
  if (t.acc) {
    NN_UNROLL for (int r = 0; r < R; ++r)
      NN_UNROLL for (int v = 0; v < NV; ++v)
        acc[r][v] = _mm256_load_ps(t.acc + r * t.ld_acc + 8 * v);
  } else {
    NN_UNROLL for (int r = 0; r < R; ++r)
      NN_UNROLL for (int v = 0; v < NV; ++v) acc[r][v] = _mm256_setzero_ps();
  }
  const float* arow[R];
  NN_UNROLL for (int r = 0; r < R; ++r) arow[r] = t.a + r * t.lda;
  const float* w = t.w;
  const char* pf = reinterpret_cast<const char*>(t.pf);
  const int pf_lines = t.pf_lines;
  for (int k = 0; k < t.kc; ++k) {
    if (k < pf_lines) _mm_prefetch(pf + 64 * k, _MM_HINT_T1);
    __m256 wv[NV];
    NN_UNROLL for (int v = 0; v < NV; ++v) wv[v] = _mm256_load_ps(w + 8 * v);
    w += NR;
    NN_UNROLL for (int r = 0; r < R; ++r) {
      const __m256 b = _mm256_broadcast_ss(arow[r] + k);
      NN_UNROLL for (int v = 0; v < NV; ++v) acc[r][v] = _mm256_fmadd_ps(b, wv[v], acc[r][v]);
    }
  }
  if (!t.ep) {
    NN_UNROLL for (int r = 0; r < R; ++r)
      NN_UNROLL for (int v = 0; v < NV; ++v) _mm256_store_ps(t.c + r * t.ldc + 8 * v, acc[r][v]);
    return;
  }
  alignas(32) float tile[R * NR];
  NN_UNROLL for (int r = 0; r < R; ++r)
    NN_UNROLL for (int v = 0; v < NV; ++v) _mm256_store_ps(tile + r * NR + 8 * v, acc[r][v]);
  switch (static_cast<Act>(t.ep->act)) {
    case Act::None: return store_epilogue<Act::None, R, NR>(tile, t);
    case Act::Relu: return store_epilogue<Act::Relu, R, NR>(tile, t);
    case Act::Gelu: return store_epilogue<Act::Gelu, R, NR>(tile, t);
    case Act::HardSwish: return store_epilogue<Act::HardSwish, R, NR>(tile, t);
    case Act::HardSigmoid: return store_epilogue<Act::HardSigmoid, R, NR>(tile, t);
    case Act::Sigmoid: return store_epilogue<Act::Sigmoid, R, NR>(tile, t);
  }
}

template <int R, int NV>
void dispatch_rows(const GemmTile& t) {
  if (t.mr == R) return tile_kernel<R, NV>(t);
  if constexpr (R > 1) dispatch_rows<R - 1, NV>(t);
}

}  // namespace

#undef NN_UNROLL

#define NN_GEMM_DEFINE_Avx2(fn, mr, nr) \
  static_assert((nr) % 8 == 0, #fn ": NR must be a multiple of 8"); \
  void fn(const GemmTile& tile) { dispatch_rows<mr, (nr) / 8>(tile); }
#define NN_GEMM_DEFINE_Avx512(fn, mr, nr)
#define NN_GEMM_DEFINE_Scalar(fn, mr, nr)
#define NN_GEMM_DEFINE(fn, isa, mr, nr) NN_GEMM_DEFINE_##isa(fn, mr, nr)
NN_GEMM_UKERNELS(NN_GEMM_DEFINE)

}  // namespace nn
