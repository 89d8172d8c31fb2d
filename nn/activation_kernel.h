// Interface between nn/activation.cpp and its ISA kernels (nn/kernel_table.h): in place,
// x[i] = act(x[i]) with act = static_cast<int>(nn::Act), never None. Declarations only.
#pragma once

#include <cstddef>

namespace nn {

void apply_act_scalar(int act, float* x, std::size_t count);
void apply_act_avx2(int act, float* x, std::size_t count);
void apply_act_avx512(int act, float* x, std::size_t count);
void apply_act_neon(int act, float* x, std::size_t count);

}  // namespace nn
