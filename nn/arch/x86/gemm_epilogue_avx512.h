// The end of an AVX-512 micro-kernel tile: the float epilogue of nn/gemm.h applied straight
// from the accumulators (32 zmm registers leave room for it), shared by the float GEMM and
// the bf16 GEMM, so both finish every element with the same instructions; the rest of the
// frame (row dispatch, the accumulators' start) is nn/gemm_tile_frame.h. Include only from
// AVX-512 ISA files (cmake/isa.cmake): every helper here is internal to the including file.
#pragma once

#include "nn/arch/x86/vecmath_avx512.h"  // first: it includes <immintrin.h> with GCC 12's false warning silenced
#include "nn/gemm_kernels.h"
#include "nn/gemm_tile_frame.h"

namespace nn {
namespace {

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
  _Pragma("GCC unroll 16") for (int r = 0; r < R; ++r) {
    float* c = t.c + r * t.ldc;
    const float* res = ep.residual ? ep.residual + r * ep.ldr : nullptr;
    _Pragma("GCC unroll 16") for (int v = 0; v < NV; ++v) {
      __m512 x = acc[r][v];
      if (ep.bias) x = _mm512_add_ps(x, bias[v]);
      if (!ep.act_after_residual) x = MathOpsAvx512::act<ACT>(x);
      if (ep.scale) x = _mm512_mul_ps(x, scale[v]);
      if (res) x = _mm512_add_ps(x, _mm512_maskz_loadu_ps(m[v], res + 16 * v));
      if (ep.act_after_residual) x = MathOpsAvx512::act<ACT>(x);
      _mm512_mask_storeu_ps(c + 16 * v, m[v], x);
    }
  }
}

// A tile's end: raw partial sums (no epilogue: an intermediate K block) or the epilogue
// for the tile's activation.
template <int R, int NV>
__attribute__((always_inline)) inline void store_tile(__m512 (&acc)[R][NV], const GemmTile& t) {
  if (!t.ep) {
    _Pragma("GCC unroll 16") for (int r = 0; r < R; ++r)
      _Pragma("GCC unroll 16") for (int v = 0; v < NV; ++v)
        _mm512_store_ps(t.c + r * t.ldc + 16 * v, acc[r][v]);
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

}  // namespace
}  // namespace nn
