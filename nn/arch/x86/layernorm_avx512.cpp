// AVX-512 LayerNorm: 16 floats per vector (nn/layernorm_rows.h).
#include "nn/arch/x86/vecops_avx512.h"
#include "nn/layernorm_rows.h"

namespace nn {

void layernorm_rows_avx512(std::size_t rows, int c, const float* x, std::ptrdiff_t ldx, float* y,
                         std::ptrdiff_t ldy, const float* gamma, const float* beta, float eps) {
  layernorm_rows_with<VecOpsAvx512>(rows, c, x, ldx, y, ldy, gamma, beta, eps);
}

}  // namespace nn
