// AVX2 activation kernel: 8 floats per ymm (nn/activation_loop.h).
#include "nn/activation_kernel.h"
#include "nn/activation_loop.h"
#include "nn/arch/x86/vecmath_avx2.h"

namespace nn {

void apply_act_avx2(int act, float* x, std::size_t count) { apply_act_with<MathOpsAvx2>(act, x, count); }

}  // namespace nn
