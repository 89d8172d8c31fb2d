// The disparity row kernel compiled for aarch64 (Advanced SIMD is baseline there; GCC
// vectorises the plain loop of nn/disparity_row_body.h with it).
#include "nn/disparity_row_body.h"

namespace nn {

void disparity_row_neon(const float* d, int n, const DisparityRowParams& p, double* z, double* y,
                        std::int64_t* flags) {
  disparity_row_body(d, n, p, z, y, flags);
}

}  // namespace nn
