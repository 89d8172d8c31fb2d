// NEON depthwise convolution: 4 channels per q register (nn/dwconv_block.h). 32 q
// registers: 7x7 stride 1 keeps 12 accumulators + 7 weights + 1 input, enough
// independent FMAs to cover a Cortex-A76/Neoverse-N1's 4-cycle FMA latency on its two
// pipes; 12 also divides ConvNeXt's widths (60 * 2^k). Not measured on ARM hardware.
#include "nn/arch/arm/vecops_neon.h"
#include "nn/dwconv_block.h"

namespace nn {
namespace {
struct TilesNeon {
  static constexpr int k7s1 = 12, k5s1 = 16, k3s1 = 16, k5s2 = 12, k3s2 = 12, generic = 8;
};
}  // namespace

void dwconv_block_neon(const DwConvJob& j, int n, int cb0, int cb1, int oy0, int oy1) {
  dwconv_block_with<VecOpsNeon, TilesNeon>(j, n, cb0, cb1, oy0, oy1);
}

}  // namespace nn
