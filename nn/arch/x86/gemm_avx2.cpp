// AVX2+FMA GEMM micro-kernels: MR rows of A broadcast against NR/8 ymm columns of the
// packed W panel, MR x NR/8 accumulators in registers, one FMA per (row, vector, k).
// Row tails are separate instantiations (R < MR); column tails use maskload/maskstore in
// the store phase (the padded panel columns are zero, so the K loop needs no masking).
// The frame around the K loop (row dispatch, start, epilogue) is nn/gemm_tile_frame.h.
#include <cstddef>

#include "nn/arch/x86/vecmath_avx2.h"  // first: it includes <immintrin.h> with GCC 12's false warning silenced
#include "nn/gemm_kernels.h"
#include "nn/gemm_tile_frame.h"

namespace nn {
namespace {

#define NN_UNROLL _Pragma("GCC unroll 16")

// One tile: R rows of A against NV ymm columns of the panel (see the top).
struct Tile {
  template <int R, int NV>
  static void run(const GemmTile& t) {
    constexpr int NR = 8 * NV;
    __m256 acc[R][NV];
    gemm_load_acc<MathOpsAvx2>(acc, t);
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
    gemm_store_acc<MathOpsAvx2>(acc, t);
  }
};

}  // namespace

#undef NN_UNROLL

#define NN_GEMM_DEFINE_Avx2(fn, mr, nr) \
  static_assert((nr) % 8 == 0, #fn ": NR must be a multiple of 8"); \
  void fn(const GemmTile& tile) { gemm_dispatch_rows<Tile, mr, (nr) / 8>(tile); }
#define NN_GEMM_DEFINE_Avx512(fn, mr, nr)
#define NN_GEMM_DEFINE_Scalar(fn, mr, nr)
#define NN_GEMM_DEFINE(fn, isa, mr, nr) NN_GEMM_DEFINE_##isa(fn, mr, nr)
NN_GEMM_UKERNELS(NN_GEMM_DEFINE)

}  // namespace nn
