#include <cfloat>
#include "shle/height_rows.h"

#include "nn/isa.h"

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
  return static_cast<int>(nn::active_isa()) >= static_cast<int>(nn::Isa::Avx2) ? &level_row_avx2 : &level_row_baseline;
}

}  // namespace shle
