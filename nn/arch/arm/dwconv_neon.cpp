// NEON depthwise convolution: 4 channels per q register (nn/dwconv_block.h). 32 q
// registers, but GCC 12 keeps at most about 8-10 accumulators of the streaming kernels in
// registers across the kernel rows (with 12, five of them go to the stack and back every
// row; checked with objdump), so R = 8 (10 for 3x3): 8 independent FMA chains still
// cover a Cortex-A76/Neoverse-N1's 4-cycle FMA latency on its two pipes. Not measured on
// ARM hardware.
#include "nn/arch/arm/vecops_neon.h"
#include "nn/dwconv_block.h"

namespace nn {
namespace {
struct TilesNeon {
  static constexpr int k7s1 = 8, k5s1 = 8, k3s1 = 10, k5s2 = 8, k3s2 = 8, generic = 8;
};
}  // namespace

void dwconv_block_neon(const DwConvJob& j, int n, int cb0, int cb1, int oy0, int oy1) {
  dwconv_block_with<VecOpsNeon, TilesNeon>(j, n, cb0, cb1, oy0, oy1);
}

}  // namespace nn
