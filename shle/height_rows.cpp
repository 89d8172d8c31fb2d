#include "shle/height_rows.h"

#include "nn/isa.h"
#include "nn/kernel_table.h"

namespace shle {

LevelRowFn level_row_kernel() { return nn::kernel_table(nn::active_isa()).disparity_row; }

}  // namespace shle
