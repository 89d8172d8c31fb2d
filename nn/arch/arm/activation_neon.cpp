// NEON activation kernel: 4 floats per q register (nn/activation_loop.h).
#include "nn/activation_kernel.h"
#include "nn/activation_loop.h"
#include "nn/arch/arm/vecmath_neon.h"

namespace nn {

void apply_act_neon(int act, float* x, std::size_t count) { apply_act_with<MathOpsNeon>(act, x, count); }

}  // namespace nn
