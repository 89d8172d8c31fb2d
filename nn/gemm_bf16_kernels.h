// Internal to the bf16 GEMM: its micro-kernel and conversion, defined in the AVX512_BF16
// file (cmake/isa.cmake). Declarations and constants only: the ISA file must not see
// nn/gemm_bf16.h's classes (their inline members would be compiled with AVX-512 flags).
#pragma once

#include <cstddef>
#include <cstdint>

#include "nn/gemm_kernels.h"

namespace nn {

// 8 rows x 48 columns (24 zmm accumulators), as the float kernel: per K pair 3 W loads
// and 8 pair broadcasts feed 24 VDPBF16PS. t.a, t.w and t.kc count K pairs (4 bytes).
constexpr int kGemmBf16Mr = 8, kGemmBf16Nr = 48;
void gemm_bf16_8x48_avx512bf16(const GemmTile& tile);

// nn::convert_to_bf16 (dst holds bfloat16 bits).
void convert_to_bf16_avx512bf16(int rows, int cols, const float* src, std::ptrdiff_t lds,
                                std::uint16_t* dst, std::ptrdiff_t ldd);

}  // namespace nn
