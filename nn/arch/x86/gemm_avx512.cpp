// AVX-512 GEMM micro-kernels: MR rows of A broadcast against NR/16 zmm columns of the
// packed W panel, MR x NR/16 accumulators in registers, one FMA per (row, vector, k).
// Row tails are separate instantiations (R < MR); column tails use k-masks in the store
// phase (the padded panel columns are zero, so the K loop needs no masking). The K loop,
// the row dispatch and the start are nn/gemm_tile_frame.h; the end is gemm_epilogue_avx512.h.
#include <cstddef>

#include "nn/gemm_kernels.h"
#include "nn/arch/x86/gemm_epilogue_avx512.h"

namespace nn {
namespace {

// One tile: R rows of A broadcast against NV zmm columns of the panel (see the top).
struct Tile {
  template <int R, int NV>
  static void run(const GemmTile& t) {
    __m512 acc[R][NV];
    gemm_load_acc<MathOpsAvx512>(acc, t);
    gemm_broadcast_k_loop<MathOpsAvx512>(acc, t);
    store_tile(acc, t);
  }
};

}  // namespace

#define NN_GEMM_DEFINE_Avx512(fn, mr, nr) \
  static_assert((nr) % 16 == 0, #fn ": NR must be a multiple of 16"); \
  void fn(const GemmTile& tile) { gemm_dispatch_rows<Tile, mr, (nr) / 16>(tile); }
#define NN_GEMM_DEFINE_Avx2(fn, mr, nr)
#define NN_GEMM_DEFINE_Scalar(fn, mr, nr)
#define NN_GEMM_DEFINE(fn, isa, mr, nr) NN_GEMM_DEFINE_##isa(fn, mr, nr)
NN_GEMM_UKERNELS(NN_GEMM_DEFINE)

}  // namespace nn
