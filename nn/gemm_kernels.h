// Internal to the GEMM: the micro-kernels and the one list that names them.
//
// NN_GEMM_UKERNELS drives everything that has to know the kernels (XNNPACK-style): the
// declarations below, the table gemm.cpp dispatches from, the tests that check every
// kernel against gemm_ref and the benchmarks that compare them. The first entry of each
// ISA is the kernel GemmWeights::pack() uses for that ISA.
//
// A micro-kernel computes an mr x nr tile (mr <= MR, nr <= NR) of C over one K block:
//   acc[r][j] = tile.acc ? tile.acc[r][j] : 0
//   for k in [0, kc): acc[r][j] = fma(a[r][k], w[k][j], acc[r][j])
// with one fused multiply-add per k in increasing k (the scalar kernel: a multiply, then an
// add). Partial sums are stored as float and reloaded exactly, so splitting K into blocks
// does not change a single bit: every element of C gets the same operation sequence no
// matter which tile, row split or thread computes it.
//
// This header is included by the ISA files (nn/arch/x86, nn/arch/arm): declarations and plain
// structs only (see cmake/isa.cmake).
#pragma once

#include <cstddef>

#include "nn/isa.h"

namespace nn {

// The epilogue of nn/gemm.h for one tile; pointers already point at the tile's first
// column (bias, scale) or first element (residual).
struct GemmTileEpilogue {
  const float* bias;
  const float* scale;
  const float* residual;
  std::ptrdiff_t ldr;
  int act;  // static_cast<int>(nn::Act)
  bool act_after_residual;
};

struct GemmTile {
  const float* a;       // row 0, column k0 of A
  std::ptrdiff_t lda;
  const float* w;       // the panel's k0 row: w[k * NR + j], 64-byte aligned
  int kc;               // K steps in this block, >= 1
  int mr, nr;           // valid rows 1..MR and columns 1..NR
  const float* acc;     // partial sums to continue from (acc[r * ld_acc + j]), or null
  std::ptrdiff_t ld_acc;
  float* c;             // destination row 0, column 0
  std::ptrdiff_t ldc;
  // Null: c is a partial-sum buffer (64-byte aligned, ldc a multiple of 16, all NR
  // columns written, no epilogue). Otherwise the final block: epilogue, then only the
  // nr valid columns of C are written.
  const GemmTileEpilogue* ep;
  // Cache lines (64 bytes each, from pf) the kernel prefetches into L2, one per K step,
  // at most kc of them: the driver points them at the W block it needs next, so the
  // stream from L3 overlaps this tile's arithmetic. pf_lines = 0: none.
  const float* pf;
  int pf_lines;
};

using GemmUkernelFn = void (*)(const GemmTile& tile);

// X(function, Isa enumerator, MR, NR). Panel layout for a kernel: [ceil(n/NR)][k][NR],
// zero-padded columns. The first kernel of each ISA is its default; pack() leaves it
// only when it would cost over a tenth more than the ISA's cheapest kernel for that N
// (gemm_ukernel_for): cost = padded columns, times 1.2 for a kernel one vector wide
// (one W load per MR FMAs leaves it load-bound). Measured with bench/gemm_bench.cpp:
// - 8x48 (24 zmm accumulators; 3 W loads and 8 broadcasts per 24 FMAs; 48 divides every
//   ConvNeXt width) matches or edges out 4x96 and 6x64 on the ConvNeXt-Tiny shapes (Zen 5
//   and Emerald Rapids); 12x32 (general-register spills on Zen 5; on Emerald Rapids no
//   better than 14x16 or 8x48 at MobileNet's N = 24..160) was left out.
// - 6x64 for the detectors' widths of 64 * 2^k, where 8x48 wastes up to a third of its
//   FMAs on padding: ResNet-50's K 256 -> N 64 1x1 conv 12.7 -> 7.8 ms, the FPN's 3x3
//   256 -> 256 (as im2col) 69.8 -> 60.7 ms (Emerald Rapids, 2 threads).
// - 14x16 for N = 16 (MobileNetV3's stem and first block): 2.42 -> 1.36 ms for the stem's
//   K 27 GEMM; at K 672, N 160 it is 15 % slower than 8x48, hence the 1.2.
// - Of the AVX2 pair (12 ymm accumulators each), 4x24 (7 loads per 12 FMAs against 8) is
//   ahead by up to 20% on K = 96 and on large W; 6x16 wins at N = 64 (18.9 -> 16.7 ms).
// The list holds the kernels of this build's architecture (nn/arch/x86, nn/arch/arm)
// and the portable scalar one.
#if defined(__x86_64__)
#define NN_GEMM_UKERNELS_ARCH(X)            \
  X(gemm_f32_8x48_avx512, Avx512, 8, 48)    \
  X(gemm_f32_4x96_avx512, Avx512, 4, 96)    \
  X(gemm_f32_6x64_avx512, Avx512, 6, 64)    \
  X(gemm_f32_14x16_avx512, Avx512, 14, 16)  \
  X(gemm_f32_4x24_avx2, Avx2, 4, 24)        \
  X(gemm_f32_6x16_avx2, Avx2, 6, 16)
#elif defined(__aarch64__)
// NEON (32 q registers of 4 floats), nn/arch/arm/gemm_neon.cpp. No ARM hardware here:
// the choice rests on the instruction counts of the compiled K loops (GCC 12, objdump;
// docs/PERFORMANCE.md), not on timings.
// - 8x12: 24 accumulators, the most that leave room for the A and W vectors (4 + 3, one
//   register spare); per 4 K steps 96 fmla by element against 8 A and 24 W loads, 132
//   instructions, no spill. 12 divides ConvNeXt's widths (96 * 2^k) and most of
//   MobileNetV3's (24, 48, 72, 96, 120, 240, ...).
// - 6x16: the same 24 accumulators for the widths where 8x12 pads more than a tenth
//   (gemm_ukernel_for): N = 16, 32 and the detectors' 64, where 8x12 issues 18 fmla per
//   row and K step against 16 (the FMA pipes are the bound: about 11 % fewer cycles);
//   96 fmla against 6 A and 48 W loads per 4 K steps, 144 instructions. From 128 up 8x12's padding is
//   at most 3 % and it keeps more rows per W load.
#define NN_GEMM_UKERNELS_ARCH(X)       \
  X(gemm_f32_8x12_neon, Neon, 8, 12)   \
  X(gemm_f32_6x16_neon, Neon, 6, 16)
#else
#define NN_GEMM_UKERNELS_ARCH(X)
#endif
#define NN_GEMM_UKERNELS(X) \
  NN_GEMM_UKERNELS_ARCH(X)  \
  X(gemm_f32_4x16_scalar, Scalar, 4, 16)

#define NN_GEMM_DECLARE_UKERNEL(fn, isa, mr, nr) void fn(const GemmTile& tile);
NN_GEMM_UKERNELS(NN_GEMM_DECLARE_UKERNEL)
#undef NN_GEMM_DECLARE_UKERNEL

struct GemmUkernelInfo {
  const char* name;
  Isa isa;
  int mr, nr;
  GemmUkernelFn fn;
};

// The list above as a table (gemm.cpp); ukernel indexes it.
int gemm_ukernel_count();
const GemmUkernelInfo& gemm_ukernel(int ukernel);
// Index of the default kernel for `isa`.
int gemm_default_ukernel(Isa isa);
// Index of the kernel GemmWeights::pack() uses for an N-column matrix: the ISA's
// default, unless its cost (above) exceeds the cheapest kernel's by more than a tenth;
// then the cheapest (the earlier one on ties).
int gemm_ukernel_for(Isa isa, int n);

// The blocking and threading driver of gemm.cpp, for any kernel whose A and W elements
// are 4 bytes wide: floats, or the bf16 GEMM's K pairs (nn/gemm_bf16.cpp passes its
// pair arrays here with K, lda and the panels counted in pairs). C, the partial sums and
// the epilogue are float either way.
struct GemmPacked {
  const float* panels;  // [ceil(n / nr)][k][nr] elements of 4 bytes
  int n, k;             // k in elements of A's rows
  int mr, nr;
  GemmUkernelFn fn;
};
struct GemmEpilogue;
// Rows [m0, m1), panels [p0, p1), single-threaded.
void gemm_blocked(int m0, int m1, int p0, int p1, const float* a, std::ptrdiff_t lda,
                  const GemmPacked& w, float* c, std::ptrdiff_t ldc, const GemmEpilogue& ep);
// All rows, split over the team's threads (rows, or columns for small M); bitwise equal to
// gemm_blocked over everything.
void gemm_split(int m, const float* a, std::ptrdiff_t lda, const GemmPacked& w, float* c,
                std::ptrdiff_t ldc, const GemmEpilogue& ep);

}  // namespace nn
