// NEON LayerNorm: 4 floats per vector (nn/layernorm_rows.h).
#include "nn/arch/arm/vecops_neon.h"
#include "nn/layernorm_rows.h"

namespace nn {

void layernorm_rows_neon(std::size_t rows, int c, const float* x, std::ptrdiff_t ldx, float* y,
                     std::ptrdiff_t ldy, const float* gamma, const float* beta, float eps) {
  layernorm_rows_with<VecOpsNeon>(rows, c, x, ldx, y, ldy, gamma, beta, eps);
}

}  // namespace nn
