// AVX2 depthwise convolution: 8 channels per ymm (nn/dwconv_block.h). 16 ymm
// registers: 7x7 stride 1 keeps 8 accumulators + 7 weights + 1 input.
#include "nn/arch/x86/vecops_avx2.h"
#include "nn/dwconv_block.h"

namespace nn {
namespace {
struct TilesAvx2 {
  static constexpr int k7s1 = 8, k5s1 = 8, k3s1 = 10, k5s2 = 8, k3s2 = 8, generic = 6;
};
}  // namespace

void dwconv_block_avx2(const DwConvJob& j, int n, int cb0, int cb1, int oy0, int oy1) {
  dwconv_block_with<VecOpsAvx2, TilesAvx2>(j, n, cb0, cb1, oy0, oy1);
}

}  // namespace nn
