// AVX-512 GEMM micro-kernels: MR rows of A broadcast against NR/16 zmm columns of the
// packed W panel, MR x NR/16 accumulators in registers, one FMA per (row, vector, k).
// Row tails are separate instantiations (R < MR); column tails use k-masks in the store
// phase (the padded panel columns are zero, so the K loop needs no masking).
#include <cstddef>

#include "nn/gemm_kernels.h"
#include "nn/arch/x86/gemm_epilogue_avx512.h"

namespace nn {
namespace {

#define NN_UNROLL _Pragma("GCC unroll 16")

// One tile: R rows of A broadcast against NV zmm columns of the panel (see the top).
struct Tile {
  template <int R, int NV>
  static void run(const GemmTile& t) {
    constexpr int NR = 16 * NV;
    // Every loop over acc is unrolled completely (NN_UNROLL): GCC keeps acc[][] in registers
    // only when all its indices are constants.
    __m512 acc[R][NV];
    gemm_load_acc<MathOpsAvx512>(acc, t);
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
    store_tile(acc, t);
  }
};

}  // namespace

#undef NN_UNROLL

#define NN_GEMM_DEFINE_Avx512(fn, mr, nr) \
  static_assert((nr) % 16 == 0, #fn ": NR must be a multiple of 16"); \
  void fn(const GemmTile& tile) { gemm_dispatch_rows<Tile, mr, (nr) / 16>(tile); }
#define NN_GEMM_DEFINE_Avx2(fn, mr, nr)
#define NN_GEMM_DEFINE_Scalar(fn, mr, nr)
#define NN_GEMM_DEFINE(fn, isa, mr, nr) NN_GEMM_DEFINE_##isa(fn, mr, nr)
NN_GEMM_UKERNELS(NN_GEMM_DEFINE)

}  // namespace nn
