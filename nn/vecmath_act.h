// exp and the activations of nn/act.h, written once over a vector ISA's "math ops" trait
// M (MathOpsAvx2, MathOpsAvx512, MathOpsNeon of nn/arch/*/vecmath_*.h: the ISA's VecOps
// plus gelu(V) and relu(V), which differ per ISA in their tables or instructions, and
// exp's clamp and power-of-two step). The rest is the same operations in the same order
// on every ISA. In an anonymous namespace: each ISA file compiles its own copy with its
// own flags.
#pragma once

#include "nn/act.h"

namespace nn {
namespace {

// exp(r) = 1 + r + r^2 * P(r) on |r| <= ln2/2: weighted-minimax fit in double (relative
// error 4.4e-9 with these float coefficients), highest degree first.
constexpr float kExpP4 = 0.00138144684f, kExpP3 = 0.00836878084f, kExpP2 = 0.0416683927f,
                kExpP1 = 0.166665196f, kExpP0 = 0.49999994f;
// ln 2 split so that n * kLn2Hi is exact for |n| < 512.
constexpr float kLn2Hi = 0.693115234f, kLn2Lo = 3.19461833e-05f, kLog2e = 1.44269502f;

// exp(x) = 2^n exp(r), n = round(x log2 e), r = x - n ln 2 in two parts. x is first
// clamped to [-M::kExpClamp, M::kExpClamp], which keeps inf - inf out of the reduction;
// M::times_pow2(p, n) overflows to inf and underflows to zero at the ends of that range.
// min/max take x as their second operand, so NaN passes (see the VecOps' max/min).
// About 1 ulp (tests/nn/test_activation.cpp).
template <class M>
inline typename M::V vec_exp(typename M::V x) {
  using V = typename M::V;
  x = M::min(M::set1(M::kExpClamp), x);
  x = M::max(M::set1(-M::kExpClamp), x);
  const V n = M::round_nearest(M::mul(x, M::set1(kLog2e)));
  V r = M::fnma(n, M::set1(kLn2Hi), x);
  r = M::fnma(n, M::set1(kLn2Lo), r);
  V p = M::fma(M::set1(kExpP4), r, M::set1(kExpP3));
  p = M::fma(p, r, M::set1(kExpP2));
  p = M::fma(p, r, M::set1(kExpP1));
  p = M::fma(p, r, M::set1(kExpP0));
  p = M::fma(p, r, M::set1(1.0f));
  p = M::fma(p, r, M::set1(1.0f));
  return M::times_pow2(p, n);
}

// 1 / (1 + exp(-x)), as PyTorch computes it.
template <class M>
inline typename M::V vec_sigmoid(typename M::V x) {
  const typename M::V e = vec_exp<M>(M::sub(M::zero(), x));
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
