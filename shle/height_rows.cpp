#include <cfloat>
#include <cstdlib>
#include <cstring>

#include "shle/height_rows.h"

namespace shle {

void level_row_baseline(const float* d, int n, const RowParams& p, double* z, double* y, std::int64_t* flags) {
  for (int i = 0; i < n; ++i) {
    // Invalid disparities give inf / NaN / negative values here; the flags drop them.
    const double zi = p.bf / static_cast<double>(d[i]);
    const double yi = p.vc * zi / p.fy - p.mount;
    const std::int64_t ok = (d[i] > 0.0f) & (d[i] <= FLT_MAX) & (zi <= p.max_depth);
    z[i] = zi;
    y[i] = yi;
    flags[i] = ok | ((ok & (yi < p.y_limit)) << 1);
  }
}

LevelRowFn level_row_kernel() {
  static const LevelRowFn fn = [] {
    const char* force = std::getenv("NN_ISA");
    if (force && std::strcmp(force, "scalar") == 0) return &level_row_baseline;
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") ? &level_row_avx2 : &level_row_baseline;
  }();
  return fn;
}

}  // namespace shle
