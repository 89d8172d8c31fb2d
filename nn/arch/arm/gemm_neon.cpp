// NEON f32 GEMM micro-kernels (contract: nn/gemm_kernels.h): MR rows of A against NR/4
// q-register columns of the packed W panel, MR x NR/4 accumulators in registers, one
// fmla (vfmaq_laneq_f32, by element) per (row, vector, k) in increasing k, so every
// element gets the operation sequence of the AVX2 and AVX-512 kernels: the same bits.
//
// A is read four K steps at a time: one 4-float load per row, each lane broadcast by the
// by-element fmla. 32 q registers do not hold the 24 accumulators, the 4-float A vectors
// of all rows and a W row at once, so the rows go in groups of G (8x12: two groups of 4,
// 24 + 4 + 3 = 31 registers) and each group re-reads the four W rows (from L1). Every
// accumulator still sees its K steps in increasing order. K % 4 trailing steps take A one
// float at a time (fmla by element 0). Row tails are separate instantiations (R < MR);
// column tails are handled in the store phase (the padded panel columns are zero). The
// frame around the K loop (row dispatch, start, epilogue) is nn/gemm_tile_frame.h.
#include <arm_neon.h>

#include <cstddef>

#include "nn/arch/arm/vecmath_neon.h"
#include "nn/gemm_kernels.h"

// GCC's pre-allocation scheduler hoists the loads of later K steps and row groups ahead
// of the FMAs; with 31 of 32 q registers in use that spills accumulators inside the K
// loop (8x12: 13 stack accesses and 11 moves, 154 instructions per 4 K steps against
// 132). Without it the loop is the fmla, the loads and the loop control
// (docs/PERFORMANCE.md); the out-of-order core does the scheduling.
#pragma GCC optimize("no-schedule-insns")

// After the pragma, so that the frame's functions get the same options as the K loop they
// are inlined into (as when they were written in this file).
#include "nn/gemm_tile_frame.h"

namespace nn {
namespace {

#define NN_UNROLL _Pragma("GCC unroll 16")

// Rows per group, chosen by reading the compiled K loops (GCC 12, -O3, objdump): 8x12 in
// groups of 4 (24 + 4 + 3 = 31 registers) has no spill, 132 instructions per 4 K steps;
// 6x16 in groups of 3 (24 + 3 + 4 = 31) spills one accumulator (a store and a reload per
// 4 K steps) and adds 7 moves, in groups of 2 (30 registers) it has none: 144
// instructions, the W rows read three times (the load pipes have room, the FMA pipes are
// the bound).
constexpr int row_group(int r, int nv) {
  const int g = nv <= 3 ? 4 : 2;
  return g > r ? r : g;
}

// K step S of four (lane S of the rows' A vectors) for rows [G0, G0 + GN).
template <int S, int G0, int GN, int R, int NV>
__attribute__((always_inline)) inline void lane_step(float32x4_t (&acc)[R][NV],
                                                     const float32x4_t (&a4)[R],
                                                     const float* wk) {
  constexpr int NR = 4 * NV;
  float32x4_t wv[NV];
  NN_UNROLL for (int v = 0; v < NV; ++v) wv[v] = vld1q_f32(wk + S * NR + 4 * v);
  NN_UNROLL for (int r = G0; r < G0 + GN; ++r)
    NN_UNROLL for (int v = 0; v < NV; ++v) acc[r][v] = vfmaq_laneq_f32(acc[r][v], wv[v], a4[r], S);
}

// Four K steps (k .. k + 3) for the row group starting at G0, then the next group.
template <int G0, int R, int NV>
__attribute__((always_inline)) inline void four_steps(float32x4_t (&acc)[R][NV],
                                                      const float* const (&arow)[R], int k,
                                                      const float* wk) {
  constexpr int G = row_group(R, NV);
  constexpr int GN = G0 + G <= R ? G : R - G0;
  // A compiler barrier per group: GCC's scheduler otherwise hoists every group's A loads
  // and keeps the first group's W vectors for the next one, and the extra live vectors
  // push accumulators onto the stack. Registers stay untouched by it.
  __asm__ volatile("" : "+r"(wk) : : "memory");
  float32x4_t a4[R];
  NN_UNROLL for (int r = G0; r < G0 + GN; ++r) a4[r] = vld1q_f32(arow[r] + k);
  lane_step<0, G0, GN>(acc, a4, wk);
  lane_step<1, G0, GN>(acc, a4, wk);
  lane_step<2, G0, GN>(acc, a4, wk);
  lane_step<3, G0, GN>(acc, a4, wk);
  if constexpr (G0 + GN < R) four_steps<G0 + GN>(acc, arow, k, wk);
}

// One tile: R rows of A against NV q-register columns of the panel (see the top).
struct Tile {
  template <int R, int NV>
  static void run(const GemmTile& t) {
    constexpr int NR = 4 * NV;
    float32x4_t acc[R][NV];
    gemm_load_acc<MathOpsNeon>(acc, t);
    const float* arow[R];
    NN_UNROLL for (int r = 0; r < R; ++r) arow[r] = t.a + r * t.lda;
    const float* w = t.w;
    const char* pf = reinterpret_cast<const char*>(t.pf);
    const int pf_lines = t.pf_lines;
    const int kc = t.kc;  // a local: the barrier in four_steps would make GCC re-read t.kc
    int k = 0;
    for (; k + 4 <= kc; k += 4) {
      // One L2 prefetch (prfm pldl2keep) per K step, as on x86; one test for all four.
      if (k + 4 <= pf_lines) {
        const char* p = pf + 64 * k;
        __builtin_prefetch(p, 0, 2);
        __builtin_prefetch(p + 64, 0, 2);
        __builtin_prefetch(p + 128, 0, 2);
        __builtin_prefetch(p + 192, 0, 2);
      } else {
        for (int s = k; s < pf_lines; ++s) __builtin_prefetch(pf + 64 * s, 0, 2);
      }
      four_steps<0>(acc, arow, k, w);
      w += 4 * NR;
    }
    for (; k < kc; ++k) {
      if (k < pf_lines) __builtin_prefetch(pf + 64 * k, 0, 2);
      float32x4_t wv[NV];
      NN_UNROLL for (int v = 0; v < NV; ++v) wv[v] = vld1q_f32(w + 4 * v);
      w += NR;
      NN_UNROLL for (int r = 0; r < R; ++r) {
        const float a = arow[r][k];
        NN_UNROLL for (int v = 0; v < NV; ++v) acc[r][v] = vfmaq_n_f32(acc[r][v], wv[v], a);
      }
    }
    gemm_store_acc<MathOpsNeon>(acc, t);
  }
};

}  // namespace

#undef NN_UNROLL

#define NN_GEMM_DEFINE_Neon(fn, mr, nr) \
  static_assert((nr) % 4 == 0, #fn ": NR must be a multiple of 4"); \
  void fn(const GemmTile& tile) { gemm_dispatch_rows<Tile, mr, (nr) / 4>(tile); }
#define NN_GEMM_DEFINE_Avx2(fn, mr, nr)
#define NN_GEMM_DEFINE_Avx512(fn, mr, nr)
#define NN_GEMM_DEFINE_Scalar(fn, mr, nr)
#define NN_GEMM_DEFINE(fn, isa, mr, nr) NN_GEMM_DEFINE_##isa(fn, mr, nr)
NN_GEMM_UKERNELS(NN_GEMM_DEFINE)

}  // namespace nn
