// A float GEMM micro-kernel (contract: nn/gemm_kernels.h) written once over a per-ISA
// "math ops" trait Ops (MathOpsAvx2, MathOpsAvx512, MathOpsNeon of nn/arch/*/vecmath_*.h:
// the VecOps of that ISA plus act<Act>(V) from its vector math): the dispatch on the
// tile's row count, the accumulators' start, the x86 K loop, and the tile's end with the
// epilogue of nn/gemm.h. The NEON K loop stays in nn/arch/arm/gemm_neon.cpp (A read four
// K steps at a time, tuned on the compiled code). The AVX-512 kernels, whose 32 registers
// leave room to apply the epilogue straight from the accumulators, have their own end
// (nn/arch/x86/gemm_epilogue_avx512.h).
// In an anonymous namespace: each ISA file compiles its own copy with its own flags.
#pragma once

#include "nn/act.h"
#include "nn/gemm_kernels.h"

namespace nn {
namespace {

// Runs Kernel::run<R, NV>(t) for the tile's row count R = t.mr (1..MR): the row tails are
// their own instantiations, so every accumulator index stays a constant.
template <class Kernel, int R, int NV>
void gemm_dispatch_rows(const GemmTile& t) {
  if (t.mr == R) return Kernel::template run<R, NV>(t);
  if constexpr (R > 1) gemm_dispatch_rows<Kernel, R - 1, NV>(t);
}

// A tile's start: zero, or the partial sums of the previous K blocks. Every loop over acc
// is unrolled completely: GCC keeps acc[][] in registers only when all its indices are
// constants.
template <class Ops, int R, int NV>
__attribute__((always_inline)) inline void gemm_load_acc(typename Ops::V (&acc)[R][NV], const GemmTile& t) {
  constexpr int L = Ops::kLanes;
  if (t.acc) {
    _Pragma("GCC unroll 16") for (int r = 0; r < R; ++r)
      _Pragma("GCC unroll 16") for (int v = 0; v < NV; ++v) acc[r][v] = Ops::load(t.acc + r * t.ld_acc + L * v);
  } else {
    _Pragma("GCC unroll 16") for (int r = 0; r < R; ++r)
      _Pragma("GCC unroll 16") for (int v = 0; v < NV; ++v) acc[r][v] = Ops::zero();
  }
}

// The broadcast K loop of the x86 kernels (the NEON kernels read A four K steps at a time,
// nn/arch/arm/gemm_neon.cpp): per k, the NV panel vectors of W row k, then per row of A one
// broadcast and NV FMAs, so every accumulator sees its K steps in increasing order; one L2
// prefetch (prefetcht1) per k of the next panel's first pf_lines lines.
template <class Ops, int R, int NV>
__attribute__((always_inline)) inline void gemm_broadcast_k_loop(typename Ops::V (&acc)[R][NV],
                                                                 const GemmTile& t) {
  using V = typename Ops::V;
  constexpr int L = Ops::kLanes, NR = L * NV;
  const float* arow[R];
  _Pragma("GCC unroll 16") for (int r = 0; r < R; ++r) arow[r] = t.a + r * t.lda;
  const float* w = t.w;
  const char* pf = reinterpret_cast<const char*>(t.pf);
  const int pf_lines = t.pf_lines;
  for (int k = 0; k < t.kc; ++k) {
    if (k < pf_lines) __builtin_prefetch(pf + 64 * k, 0, 2);
    V wv[NV];
    _Pragma("GCC unroll 16") for (int v = 0; v < NV; ++v) wv[v] = Ops::load(w + L * v);
    w += NR;
    _Pragma("GCC unroll 16") for (int r = 0; r < R; ++r) {
      const V b = Ops::broadcast(arow[r] + k);
      _Pragma("GCC unroll 16") for (int v = 0; v < NV; ++v) acc[r][v] = Ops::fma(b, wv[v], acc[r][v]);
    }
  }
}

// The epilogue of nn/gemm.h on R rows of raw sums (tile, row stride NR): bias, act, scale,
// residual (read just before the same element of C is written, so it may alias C), act.
// Column tails through the ISA's partial loads and stores: nothing past column nr is read
// or written. Out of line: with 16 ymm registers GCC otherwise spills the K loop's
// accumulators inside the loop to make room for the epilogue (NEON's 31 of 32 q registers
// likewise).
template <class Ops, Act ACT, int R, int NR>
__attribute__((noinline)) void gemm_store_epilogue(const float* tile, const GemmTile& t) {
  using V = typename Ops::V;
  constexpr int L = Ops::kLanes;
  const GemmTileEpilogue& ep = *t.ep;
  for (int r = 0; r < R; ++r) {
    float* c = t.c + r * t.ldc;
    const float* res = ep.residual ? ep.residual + r * ep.ldr : nullptr;
    for (int v = 0; v * L < t.nr; ++v) {
      const int valid = t.nr - L * v;
      V x = Ops::load(tile + r * NR + L * v);
      if (valid >= L) {
        if (ep.bias) x = Ops::add(x, Ops::loadu(ep.bias + L * v));
        if (!ep.act_after_residual) x = Ops::template act<ACT>(x);
        if (ep.scale) x = Ops::mul(x, Ops::loadu(ep.scale + L * v));
        if (res) x = Ops::add(x, Ops::loadu(res + L * v));
        if (ep.act_after_residual) x = Ops::template act<ACT>(x);
        Ops::storeu(c + L * v, x);
      } else {
        const typename Ops::Mask m = Ops::mask(valid);
        if (ep.bias) x = Ops::add(x, Ops::load_part(ep.bias + L * v, m));
        if (!ep.act_after_residual) x = Ops::template act<ACT>(x);
        if (ep.scale) x = Ops::mul(x, Ops::load_part(ep.scale + L * v, m));
        if (res) x = Ops::add(x, Ops::load_part(res + L * v, m));
        if (ep.act_after_residual) x = Ops::template act<ACT>(x);
        Ops::store_part(c + L * v, m, x);
      }
    }
  }
}

// A tile's end: raw partial sums into C (no epilogue: an intermediate K block), or the
// accumulators through a stack tile into the epilogue of the tile's activation.
template <class Ops, int R, int NV>
__attribute__((always_inline)) inline void gemm_store_acc(typename Ops::V (&acc)[R][NV], const GemmTile& t) {
  constexpr int L = Ops::kLanes, NR = L * NV;
  if (!t.ep) {
    _Pragma("GCC unroll 16") for (int r = 0; r < R; ++r)
      _Pragma("GCC unroll 16") for (int v = 0; v < NV; ++v) Ops::store(t.c + r * t.ldc + L * v, acc[r][v]);
    return;
  }
  alignas(sizeof(typename Ops::V)) float tile[R * NR];
  _Pragma("GCC unroll 16") for (int r = 0; r < R; ++r)
    _Pragma("GCC unroll 16") for (int v = 0; v < NV; ++v) Ops::store(tile + r * NR + L * v, acc[r][v]);
  switch (static_cast<Act>(t.ep->act)) {
    case Act::None: return gemm_store_epilogue<Ops, Act::None, R, NR>(tile, t);
    case Act::Relu: return gemm_store_epilogue<Ops, Act::Relu, R, NR>(tile, t);
    case Act::Gelu: return gemm_store_epilogue<Ops, Act::Gelu, R, NR>(tile, t);
    case Act::HardSwish: return gemm_store_epilogue<Ops, Act::HardSwish, R, NR>(tile, t);
    case Act::HardSigmoid: return gemm_store_epilogue<Ops, Act::HardSigmoid, R, NR>(tile, t);
    case Act::Sigmoid: return gemm_store_epilogue<Ops, Act::Sigmoid, R, NR>(tile, t);
  }
}

}  // namespace
}  // namespace nn
