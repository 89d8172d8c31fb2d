// The activation kernel written once for every ISA (nn/activation_kernel.h): two full
// vectors at a time, then one, then the last count % lanes elements through a zeroed
// lanes-float copy, so a tail element gets the bits it would get inside a full vector and
// nothing past the end is read or written. ActOps is the ISA's: V, kLanes, loadu, storeu and
// act<Act>(V) from its vector math: MathOps* of nn/arch/*/vecmath_*.h, shared with the GEMM epilogues.
// In an anonymous namespace: each ISA file compiles its own copy with its own flags.
#pragma once

#include <cstddef>
#include <cstring>

#include "nn/act.h"

namespace nn {
namespace {

template <class ActOps, Act ACT>
void act_loop(float* x, std::size_t count) {
  constexpr std::size_t L = ActOps::kLanes;
  std::size_t i = 0;
  for (; i + 2 * L <= count; i += 2 * L) {
    ActOps::storeu(x + i, ActOps::template act<ACT>(ActOps::loadu(x + i)));
    ActOps::storeu(x + i + L, ActOps::template act<ACT>(ActOps::loadu(x + i + L)));
  }
  for (; i + L <= count; i += L) ActOps::storeu(x + i, ActOps::template act<ACT>(ActOps::loadu(x + i)));
  if (i < count) {
    const std::size_t left = count - i;
    float tail[L] = {};
    std::memcpy(tail, x + i, left * sizeof(float));
    ActOps::storeu(tail, ActOps::template act<ACT>(ActOps::loadu(tail)));
    std::memcpy(x + i, tail, left * sizeof(float));
  }
}

template <class ActOps>
void apply_act_with(int act, float* x, std::size_t count) {
  switch (static_cast<Act>(act)) {
    case Act::None: return;
    case Act::Relu: return act_loop<ActOps, Act::Relu>(x, count);
    case Act::Gelu: return act_loop<ActOps, Act::Gelu>(x, count);
    case Act::HardSwish: return act_loop<ActOps, Act::HardSwish>(x, count);
    case Act::HardSigmoid: return act_loop<ActOps, Act::HardSigmoid>(x, count);
    case Act::Sigmoid: return act_loop<ActOps, Act::Sigmoid>(x, count);
  }
}

}  // namespace
}  // namespace nn
