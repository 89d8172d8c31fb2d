// Element-wise activations over contiguous floats (dispatched by ISA), and their
// scalar references. GELU is the exact erf form, within 1e-6 of PyTorch's.
#pragma once

#include <cstddef>

#include "nn/act.h"
#include "nn/isa.h"

namespace nn {

// Scalar definition of every activation; the reference the kernels are tested against.
float act_ref(Act act, float x);

// x[i] = act(x[i]) for i in [0, count), using the active ISA.
// The first form uses active_isa() (outside parallel regions); inside one, pass the ISA.
void apply_act(Act act, float* x, std::size_t count);
void apply_act(Act act, float* x, std::size_t count, Isa isa);
void apply_act_ref(Act act, float* x, std::size_t count);

}  // namespace nn
