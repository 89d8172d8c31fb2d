// Internal to the bf16 GEMM: its micro-kernel and conversion, defined in the AVX512_BF16
// file (cmake/isa.cmake). Declarations and constants only.
#pragma once

#include <cstddef>

#include "nn/gemm_bf16.h"
#include "nn/gemm_kernels.h"

namespace nn {

// 8 rows x 48 columns (24 zmm accumulators), as the float kernel: per K pair 3 W loads
// and 8 pair broadcasts feed 24 VDPBF16PS. t.a, t.w and t.kc count K pairs (4 bytes).
constexpr int kGemmBf16Mr = 8, kGemmBf16Nr = 48;
void gemm_bf16_8x48_avx512bf16(const GemmTile& tile);

void convert_to_bf16_avx512bf16(int rows, int cols, const float* src, std::ptrdiff_t lds,
                                bf16* dst, std::ptrdiff_t ldd);

}  // namespace nn
