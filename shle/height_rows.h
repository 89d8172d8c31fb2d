// The per-row kernel of stage 2 for a level camera: nn's disparity row kernel
// (nn/disparity_row_kernel.h: Z = bf / d, Y = (v - cy) * Z / fy - mount and the flag
// word), taken from the kernel table of nn::active_isa() (the CPU capped by the calling
// thread's nn::ExecOptions). Every ISA's form gives the same bits.
#pragma once

#include "nn/disparity_row_kernel.h"

namespace shle {

using RowParams = nn::DisparityRowParams;
using LevelRowFn = nn::DisparityRowFn;
LevelRowFn level_row_kernel();

}  // namespace shle
