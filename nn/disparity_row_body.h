// The body of every ISA's disparity_row_* (nn/disparity_row_kernel.h), in an anonymous
// namespace: each including file compiles it with its own ISA flags and lets the compiler
// vectorise the loop; the operations and their order are the same in every copy.
#pragma once

#include <cfloat>
#include <cstdint>

#include "nn/disparity_row_kernel.h"

namespace nn {
namespace {

inline void disparity_row_body(const float* d, int n, const DisparityRowParams& p, double* z, double* y,
                               std::int64_t* flags) {
  const double bf = p.bf, vc = p.vc, fy = p.fy, mount = p.mount, lim = p.y_limit, maxd = p.max_depth;
  for (int i = 0; i < n; ++i) {
    // Invalid disparities give inf / NaN / negative values here; the flags drop them.
    const double zi = bf / static_cast<double>(d[i]);
    const double yi = vc * zi / fy - mount;
    const std::int64_t ok = (d[i] > 0.0f) & (d[i] <= FLT_MAX) & (zi <= maxd);
    z[i] = zi;
    y[i] = yi;
    flags[i] = ok | ((ok & (yi < lim)) << 1);
  }
}

}  // namespace
}  // namespace nn
