// The disparity row kernel compiled with AVX2 (nn/disparity_row_body.h).
#include "nn/disparity_row_body.h"

namespace nn {

void disparity_row_avx2(const float* d, int n, const DisparityRowParams& p, double* z, double* y,
                        std::int64_t* flags) {
  disparity_row_body(d, n, p, z, y, flags);
}

}  // namespace nn
