// AVX-512 activation kernel: 16 floats per zmm (nn/activation_loop.h).
#include "nn/activation_kernel.h"
#include "nn/activation_loop.h"
#include "nn/arch/x86/vecmath_avx512.h"

namespace nn {

void apply_act_avx512(int act, float* x, std::size_t count) { apply_act_with<MathOpsAvx512>(act, x, count); }

}  // namespace nn
