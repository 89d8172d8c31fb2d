// Interface between nn/layernorm.cpp and its ISA kernels (nn/kernel_table.h). Declarations only: the
// ISA files include it, so it must not define inline functions or templates.
#pragma once

#include <cstddef>

namespace nn {

// Same contract as nn::layernorm (gamma/beta may be null, y may alias x). A row's
// result depends only on that row: rows are processed four at a time, a short last
// group being padded with repeats of its last row whose results are not stored.
using LayerNormRowsFn = void (*)(std::size_t rows, int c, const float* x, std::ptrdiff_t ldx, float* y,
                                 std::ptrdiff_t ldy, const float* gamma, const float* beta, float eps);
void layernorm_rows_scalar(std::size_t rows, int c, const float* x, std::ptrdiff_t ldx, float* y,
                           std::ptrdiff_t ldy, const float* gamma, const float* beta, float eps);
void layernorm_rows_neon(std::size_t rows, int c, const float* x, std::ptrdiff_t ldx, float* y,
                         std::ptrdiff_t ldy, const float* gamma, const float* beta, float eps);
void layernorm_rows_avx512(std::size_t rows, int c, const float* x, std::ptrdiff_t ldx, float* y,
                           std::ptrdiff_t ldy, const float* gamma, const float* beta, float eps);
void layernorm_rows_avx2(std::size_t rows, int c, const float* x, std::ptrdiff_t ldx, float* y,
                         std::ptrdiff_t ldy, const float* gamma, const float* beta, float eps);

}  // namespace nn
