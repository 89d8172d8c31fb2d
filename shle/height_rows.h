// The per-row kernel of stage 2 for a level camera: for each pixel of a row,
// Z = bf / d, Y = (v - cy) * Z / fy - mount (the released arithmetic) and a flag
// word (bit 0: valid disparity and Z <= max_depth, bit 1: also Y < y_limit).
// The baseline and AVX2 builds compute bitwise identical results (IEEE division,
// no contraction); the AVX2 one is picked at run time when the CPU has it.
#pragma once

#include <cstdint>

namespace shle {

struct RowParams {
  double bf, vc, fy, mount, y_limit, max_depth;
};

void level_row_baseline(const float* d, int n, const RowParams& p, double* z, double* y, std::int64_t* flags);
void level_row_avx2(const float* d, int n, const RowParams& p, double* z, double* y, std::int64_t* flags);

// level_row_avx2 when nn::active_isa() (the CPU capped by the calling thread's
// nn::ExecOptions) has AVX2, else level_row_baseline.
using LevelRowFn = void (*)(const float*, int, const RowParams&, double*, double*, std::int64_t*);
LevelRowFn level_row_kernel();

}  // namespace shle
