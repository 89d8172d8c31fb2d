// The activations of nn/act.h built from a vector ISA's own exp, GELU and ReLU, written
// once over its "math ops" trait M (MathOpsAvx2, MathOpsAvx512, MathOpsNeon of
// nn/arch/*/vecmath_*.h: the ISA's VecOps plus exp(V), gelu(V) and relu(V), which differ
// per ISA in their instructions or tables). Sigmoid, hardsigmoid and hardswish are the
// same operations in the same order on every ISA, so they give the same bits wherever
// exp does. In an anonymous namespace: each ISA file compiles its own copy with its own
// flags.
#pragma once

#include "nn/act.h"

namespace nn {
namespace {

// 1 / (1 + exp(-x)), as PyTorch computes it.
template <class M>
inline typename M::V vec_sigmoid(typename M::V x) {
  const typename M::V e = M::exp(M::sub(M::zero(), x));
  return M::div(M::set1(1.0f), M::add(M::set1(1.0f), e));
}

// min(6, max(0, x + 3)), the input of the max and min as their second operand: NaN
// propagates, as in PyTorch (see the VecOps' max/min).
template <class M>
inline typename M::V vec_relu6_shift3(typename M::V x) {
  const typename M::V t = M::max(M::zero(), M::add(x, M::set1(3.0f)));
  return M::min(M::set1(6.0f), t);
}

// PyTorch divides by 6 (not a multiply by 1/6); so do we, for the same rounding.
template <class M>
inline typename M::V vec_hardsigmoid(typename M::V x) {
  return M::div(vec_relu6_shift3<M>(x), M::set1(6.0f));
}

template <class M>
inline typename M::V vec_hardswish(typename M::V x) {
  return M::div(M::mul(x, vec_relu6_shift3<M>(x)), M::set1(6.0f));
}

template <class M, Act ACT>
inline typename M::V vec_act(typename M::V x) {
  if constexpr (ACT == Act::Relu) return M::relu(x);
  else if constexpr (ACT == Act::Gelu) return M::gelu(x);
  else if constexpr (ACT == Act::HardSwish) return vec_hardswish<M>(x);
  else if constexpr (ACT == Act::HardSigmoid) return vec_hardsigmoid<M>(x);
  else if constexpr (ACT == Act::Sigmoid) return vec_sigmoid<M>(x);
  else return x;
}

}  // namespace
}  // namespace nn
