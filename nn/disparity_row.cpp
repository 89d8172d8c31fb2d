// The baseline form of the disparity row kernel (nn/disparity_row_body.h).
#include "nn/disparity_row_body.h"

namespace nn {

void disparity_row_scalar(const float* d, int n, const DisparityRowParams& p, double* z, double* y,
                          std::int64_t* flags) {
  disparity_row_body(d, n, p, z, y, flags);
}

}  // namespace nn
