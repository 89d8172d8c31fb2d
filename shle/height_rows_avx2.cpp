// Compiled with -mavx2 (cmake/isa.cmake): only this plain function is exported.
#include <cfloat>
#include <cstdint>

#include "shle/height_rows.h"

namespace shle {

void level_row_avx2(const float* d, int n, const RowParams& p, double* z, double* y, std::int64_t* flags) {
  const double bf = p.bf, vc = p.vc, fy = p.fy, mount = p.mount, lim = p.y_limit, maxd = p.max_depth;
  for (int i = 0; i < n; ++i) {
    const double zi = bf / static_cast<double>(d[i]);
    const double yi = vc * zi / fy - mount;
    const std::int64_t ok = (d[i] > 0.0f) & (d[i] <= FLT_MAX) & (zi <= maxd);
    z[i] = zi;
    y[i] = yi;
    flags[i] = ok | ((ok & (yi < lim)) << 1);
  }
}

}  // namespace shle
