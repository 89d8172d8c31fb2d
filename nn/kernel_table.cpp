// The kernel tables of this build's architecture. x86-64: scalar, AVX2+FMA, AVX-512
// (+ AVX512_BF16 products when the CPU has them); aarch64: scalar, NEON.
#include "nn/kernel_table.h"

#include "nn/cpu_features.h"

namespace nn {

namespace {

constexpr KernelTable kScalar = {
    Isa::Scalar,           1,
    apply_act_scalar,      layernorm_rows_scalar,
    nullptr,               resize_bilinear_row_scalar,
    winograd_input_tile_scalar, winograd_output_tile_scalar,
    detection::roi_bin_scalar,  disparity_row_scalar,
    peak_fma_scalar,       nullptr,
    nullptr,
};

#if defined(__x86_64__)
constexpr KernelTable kAvx2 = {
    Isa::Avx2,             8,
    apply_act_avx2,        layernorm_rows_avx2,
    dwconv_block_avx2,     resize_bilinear_row_avx2,
    winograd_input_tile_avx2, winograd_output_tile_avx2,
    detection::roi_bin_avx2,  disparity_row_avx2,
    peak_fma_avx2,         nullptr,
    nullptr,
};

KernelTable avx512_table() {
  KernelTable t = {
      Isa::Avx512,           16,
      apply_act_avx512,      layernorm_rows_avx512,
      dwconv_block_avx512,   resize_bilinear_row_avx2,  // AVX2 rows here and for the disparity: no AVX-512 form
      winograd_input_tile_avx512, winograd_output_tile_avx512,
      detection::roi_bin_avx512,  disparity_row_avx2,
      peak_fma_avx512,       nullptr,
      nullptr,
  };
  if (cpu_features().avx512_bf16) {
    t.gemm_bf16 = gemm_bf16_8x48_avx512bf16;
    t.convert_to_bf16 = convert_to_bf16_avx512bf16;
  }
  return t;
}
#endif

#if defined(__aarch64__)
constexpr KernelTable kNeon = {
    Isa::Neon,             4,
    apply_act_neon,        layernorm_rows_neon,
    dwconv_block_neon,     resize_bilinear_row_neon,
    winograd_input_tile_neon, winograd_output_tile_neon,
    detection::roi_bin_neon,  disparity_row_neon,
    peak_fma_neon,         nullptr,
    nullptr,
};
#endif

}  // namespace

const KernelTable& kernel_table(Isa isa) {
  switch (cap_isa(isa)) {
#if defined(__x86_64__)
    case Isa::Avx2: return kAvx2;
    case Isa::Avx512: {
      static const KernelTable t = avx512_table();
      return t;
    }
#endif
#if defined(__aarch64__)
    case Isa::Neon: return kNeon;
#endif
    default: return kScalar;
  }
}

}  // namespace nn
