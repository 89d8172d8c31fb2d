// LayerNorm over the innermost (channel) axis of NHWC rows: per row,
// y = (x - mean) / sqrt(var + eps) * gamma + beta with the biased variance (/C),
// as torch.nn.LayerNorm and torchvision's LayerNorm2d compute it.
//
// Float kernels, per row: mean m (vector partial sums folded by halves), then the
// sums of d = x - m and d^2, with delta = sum(d) / c correcting the rounding of m
// ("corrected two-pass"): within ~3e-7 of a double-precision evaluation relative to
// the row's largest output, even when |mean| is large against the spread. A row's
// result depends only on that row (not on grouping or thread split).
#pragma once

#include <cstddef>

#include "nn/isa.h"

namespace nn {

// x and y are [rows x c] with row strides ldx, ldy (in floats); y may alias x.
// gamma/beta may be null (then 1 and 0). Single-threaded; callers split rows.
// The first form uses active_isa() and is for code outside parallel regions; inside
// one, pass the model's ISA (worker threads do not see the caller's ExecScope).
void layernorm(std::size_t rows, int c, const float* x, std::ptrdiff_t ldx, float* y,
               std::ptrdiff_t ldy, const float* gamma, const float* beta, float eps);
void layernorm(std::size_t rows, int c, const float* x, std::ptrdiff_t ldx, float* y,
               std::ptrdiff_t ldy, const float* gamma, const float* beta, float eps, Isa isa);
void layernorm_ref(std::size_t rows, int c, const float* x, std::ptrdiff_t ldx, float* y,
                   std::ptrdiff_t ldy, const float* gamma, const float* beta, float eps);

// Parallel over rows; bitwise identical to layernorm().
void layernorm_parallel(std::size_t rows, int c, const float* x, std::ptrdiff_t ldx, float* y,
                        std::ptrdiff_t ldy, const float* gamma, const float* beta, float eps);

}  // namespace nn
