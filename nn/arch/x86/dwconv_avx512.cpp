// AVX-512 depthwise convolution: 16 channels per zmm (nn/dwconv_block.h). 32 zmm
// registers: 7x7 stride 1 keeps 12 accumulators + 7 weights + 1 input.
#include "nn/arch/x86/vecops_avx512.h"
#include "nn/dwconv_block.h"

namespace nn {
namespace {
struct TilesAvx512 {
  static constexpr int k7s1 = 12, k5s1 = 16, k3s1 = 16, k5s2 = 12, k3s2 = 12, generic = 8;
};
}  // namespace

void dwconv_block_avx512(const DwConvJob& j, int n, int cb0, int cb1, int oy0, int oy1) {
  dwconv_block_with<VecOpsAvx512, TilesAvx512>(j, n, cb0, cb1, oy0, oy1);
}

}  // namespace nn
