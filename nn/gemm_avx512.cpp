// AVX-512 GEMM micro-kernels: MR rows of A broadcast against NR/16 zmm columns of the
// packed W panel, MR x NR/16 accumulators in registers, one FMA per (row, vector, k).
// Row tails are separate instantiations (R < MR); column tails use k-masks in the store
// phase (the padded panel columns are zero, so the K loop needs no masking).
#include <cstddef>

#include "nn/gemm_kernels.h"
#include "nn/vecmath_avx512.h"

namespace nn {
namespace {

#define NN_UNROLL _Pragma("GCC unroll 16")

inline __mmask16 column_mask(int valid) {
  if (valid <= 0) return 0;
  return valid >= 16 ? __mmask16(0xFFFF) : __mmask16((1u << valid) - 1u);
}

// The epilogue of nn/gemm.h, straight from the accumulators: per vector, bias, act, scale,
// residual (read just before the same element of C is written, so it may alias C), act.
template <Act ACT, int R, int NV>
__attribute__((always_inline)) inline void store_epilogue(__m512 (&acc)[R][NV],
                                                          const GemmTile& t) {
  const GemmTileEpilogue& ep = *t.ep;
  __mmask16 m[NV];
  __m512 bias[NV], scale[NV];
  for (int v = 0; v < NV; ++v) {
    m[v] = column_mask(t.nr - 16 * v);
    bias[v] = ep.bias ? _mm512_maskz_loadu_ps(m[v], ep.bias + 16 * v) : _mm512_setzero_ps();
    scale[v] = ep.scale ? _mm512_maskz_loadu_ps(m[v], ep.scale + 16 * v) : _mm512_setzero_ps();
  }
  NN_UNROLL for (int r = 0; r < R; ++r) {
    float* c = t.c + r * t.ldc;
    const float* res = ep.residual ? ep.residual + r * ep.ldr : nullptr;
    NN_UNROLL for (int v = 0; v < NV; ++v) {
      __m512 x = acc[r][v];
      if (ep.bias) x = _mm512_add_ps(x, bias[v]);
      if (!ep.act_after_residual) x = v512_act<ACT>(x);
      if (ep.scale) x = _mm512_mul_ps(x, scale[v]);
      if (res) x = _mm512_add_ps(x, _mm512_maskz_loadu_ps(m[v], res + 16 * v));
      if (ep.act_after_residual) x = v512_act<ACT>(x);
      _mm512_mask_storeu_ps(c + 16 * v, m[v], x);
    }
  }
}

template <int R, int NV>
void tile_kernel(const GemmTile& t) {
  constexpr int NR = 16 * NV;
  // Every loop over acc is unrolled completely (NN_UNROLL): GCC keeps acc[][] in registers
  // only when all its indices are constants.
  __m512 acc[R][NV];
  if (t.acc) {
    NN_UNROLL for (int r = 0; r < R; ++r)
      NN_UNROLL for (int v = 0; v < NV; ++v)
        acc[r][v] = _mm512_load_ps(t.acc + r * t.ld_acc + 16 * v);
  } else {
    NN_UNROLL for (int r = 0; r < R; ++r)
      NN_UNROLL for (int v = 0; v < NV; ++v) acc[r][v] = _mm512_setzero_ps();
  }
  const float* arow[R];
  NN_UNROLL for (int r = 0; r < R; ++r) arow[r] = t.a + r * t.lda;
  const float* w = t.w;
  const char* pf = reinterpret_cast<const char*>(t.pf);
  const int pf_lines = t.pf_lines;
  for (int k = 0; k < t.kc; ++k) {
    if (k < pf_lines) _mm_prefetch(pf + 64 * k, _MM_HINT_T1);
    __m512 wv[NV];
    NN_UNROLL for (int v = 0; v < NV; ++v) wv[v] = _mm512_load_ps(w + 16 * v);
    w += NR;
    NN_UNROLL for (int r = 0; r < R; ++r) {
      const __m512 b = _mm512_set1_ps(arow[r][k]);
      NN_UNROLL for (int v = 0; v < NV; ++v) acc[r][v] = _mm512_fmadd_ps(b, wv[v], acc[r][v]);
    }
  }
  if (!t.ep) {
    NN_UNROLL for (int r = 0; r < R; ++r)
      NN_UNROLL for (int v = 0; v < NV; ++v) _mm512_store_ps(t.c + r * t.ldc + 16 * v, acc[r][v]);
    return;
  }
  switch (static_cast<Act>(t.ep->act)) {
    case Act::None: return store_epilogue<Act::None>(acc, t);
    case Act::Relu: return store_epilogue<Act::Relu>(acc, t);
    case Act::Gelu: return store_epilogue<Act::Gelu>(acc, t);
    case Act::HardSwish: return store_epilogue<Act::HardSwish>(acc, t);
    case Act::HardSigmoid: return store_epilogue<Act::HardSigmoid>(acc, t);
    case Act::Sigmoid: return store_epilogue<Act::Sigmoid>(acc, t);
  }
}

// Picks the instantiation for the tile's row count (1..MR).
template <int R, int NV>
void dispatch_rows(const GemmTile& t) {
  if (t.mr == R) return tile_kernel<R, NV>(t);
  if constexpr (R > 1) dispatch_rows<R - 1, NV>(t);
}

}  // namespace

#undef NN_UNROLL

#define NN_GEMM_DEFINE_Avx512(fn, mr, nr) \
  static_assert((nr) % 16 == 0, #fn ": NR must be a multiple of 16"); \
  void fn(const GemmTile& tile) { dispatch_rows<mr, (nr) / 16>(tile); }
#define NN_GEMM_DEFINE_Avx2(fn, mr, nr)
#define NN_GEMM_DEFINE_Scalar(fn, mr, nr)
#define NN_GEMM_DEFINE(fn, isa, mr, nr) NN_GEMM_DEFINE_##isa(fn, mr, nr)
NN_GEMM_UKERNELS(NN_GEMM_DEFINE)

}  // namespace nn
