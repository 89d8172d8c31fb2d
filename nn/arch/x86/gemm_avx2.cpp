// AVX2+FMA GEMM micro-kernels: MR rows of A broadcast against NR/8 ymm columns of the
// packed W panel, MR x NR/8 accumulators in registers, one FMA per (row, vector, k).
// Row tails are separate instantiations (R < MR); column tails use maskload/maskstore in
// the store phase (the padded panel columns are zero, so the K loop needs no masking).
// The K loop and the frame around it (row dispatch, start, epilogue) are
// nn/gemm_tile_frame.h, shared with the AVX-512 kernels.
#include <cstddef>

#include "nn/arch/x86/vecmath_avx2.h"  // first: it includes <immintrin.h> with GCC 12's false warning silenced
#include "nn/gemm_kernels.h"
#include "nn/gemm_tile_frame.h"

namespace nn {
namespace {

// One tile: R rows of A against NV ymm columns of the panel (see the top).
struct Tile {
  template <int R, int NV>
  static void run(const GemmTile& t) {
    __m256 acc[R][NV];
    gemm_load_acc<MathOpsAvx2>(acc, t);
    gemm_broadcast_k_loop<MathOpsAvx2>(acc, t);
    gemm_store_acc<MathOpsAvx2>(acc, t);
  }
};

}  // namespace

#define NN_GEMM_DEFINE_Avx2(fn, mr, nr) \
  static_assert((nr) % 8 == 0, #fn ": NR must be a multiple of 8"); \
  void fn(const GemmTile& tile) { gemm_dispatch_rows<Tile, mr, (nr) / 8>(tile); }
#define NN_GEMM_DEFINE_Avx512(fn, mr, nr)
#define NN_GEMM_DEFINE_Scalar(fn, mr, nr)
#define NN_GEMM_DEFINE(fn, isa, mr, nr) NN_GEMM_DEFINE_##isa(fn, mr, nr)
NN_GEMM_UKERNELS(NN_GEMM_DEFINE)

}  // namespace nn
