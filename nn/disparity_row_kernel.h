// The per-row kernel of SHLE's stage 2 for a level camera (shle/height_rows.h), here
// because it is an ISA kernel like the others and comes from the kernel table: for each
// pixel of a row, Z = bf / d, Y = (v - cy) * Z / fy - mount (the released arithmetic)
// and a flag word (bit 0: valid disparity and Z <= max_depth, bit 1: also Y < y_limit).
// Every ISA's form computes bitwise identical results (IEEE division, no contraction).
// Declarations only (cmake/isa.cmake).
#pragma once

#include <cstdint>

namespace nn {

struct DisparityRowParams {
  double bf, vc, fy, mount, y_limit, max_depth;
};

using DisparityRowFn = void (*)(const float* d, int n, const DisparityRowParams& p, double* z, double* y,
                                std::int64_t* flags);

void disparity_row_scalar(const float* d, int n, const DisparityRowParams& p, double* z, double* y,
                          std::int64_t* flags);
void disparity_row_avx2(const float* d, int n, const DisparityRowParams& p, double* z, double* y,
                        std::int64_t* flags);
void disparity_row_neon(const float* d, int n, const DisparityRowParams& p, double* z, double* y,
                        std::int64_t* flags);

}  // namespace nn
