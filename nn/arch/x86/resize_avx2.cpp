// AVX2+FMA inner loop of bilinear resizing: 8 channels per vector (nn/resize_row.h).
#include "nn/arch/x86/vecops_avx2.h"
#include "nn/resize_row.h"

namespace nn {

void resize_bilinear_row_avx2(const float* row0, const float* row1, float h0, float h1,
                              const long long* x0, const long long* x1, const float* w0,
                              const float* w1, int count, int c, float* out) {
  resize_bilinear_row_with<VecOpsAvx2>(row0, row1, h0, h1, x0, x1, w0, w1, count, c, out);
}

}  // namespace nn
