// exp and the activations of nn/act.h, written once over a vector ISA's "math ops" trait
// M (MathOpsAvx2, MathOpsAvx512, MathOpsNeon of nn/arch/*/vecmath_*.h: the ISA's VecOps
// plus gelu(V) and relu(V), which differ per ISA in their tables or instructions, and
// exp's clamp and power-of-two step). The rest is the same operations in the same order
// on every ISA. AVX2 and NEON also share their GELU (vec_gelu_table8); AVX-512's reaches
// 32 table entries per lookup and has its own (nn/arch/x86/vecmath_avx512.h). In an
// anonymous namespace: each ISA file compiles its own copy with its own flags.
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

// h(a) = Phi(-a) = erfc(a / sqrt 2) / 2 on [0, 6): 8 intervals of width 3/4, a degree-6
// polynomial in u = a * 4/3 - 0.5 - i per interval i (weighted GELU error a * |dh| <=
// 1.6e-8). Row j holds the u^j coefficients of the 8 intervals: one 8-entry lookup per
// coefficient.
alignas(32) constexpr float kGeluTable8[7][8] = {
    {0.353830218f, 0.130294532f, 0.0303963646f, 0.00433244929f, 0.000369078683f,
     1.85367535e-05f, 5.44038755e-07f, 9.27496302e-09f},
    {-0.278891265f, -0.158907637f, -0.0515897088f, -0.00954308826f, -0.0010058406f,
     -6.04102061e-05f, -2.06773188e-06f, -4.0346201e-08f},
    {0.0392201766f, 0.0670387f, 0.036274083f, 0.00939403474f, 0.00127300539f,
     9.34398486e-05f, 3.77916899e-06f, 8.50568966e-08f},
    {0.022466151f, -0.00395167386f, -0.012166841f, -0.00527177891f, -0.000979768345f,
     -9.05413181e-05f, -4.38679581e-06f, -1.14271984e-07f},
    {-0.00526561122f, -0.00544611132f, 0.00087547343f, 0.00171325111f, 0.000500864408f,
     6.13693774e-05f, 3.66778431e-06f, 1.13190168e-07f},
    {-0.00156722416f, 0.00120694831f, 0.000779021415f, -0.00021681338f, -0.000171171647f,
     -3.15746765e-05f, -2.51333267e-06f, -9.82732615e-08f},
    {0.000481751194f, 0.000221013193f, -0.000240751688f, -5.43378774e-05f, 3.35252989e-05f,
     1.12106572e-05f, 1.20260199e-06f, 5.78770916e-08f},
};

// gelu(x) = x * Phi(x), Phi(x) = 1 - h(|x|) for x >= 0 and h(|x|) for x < 0, h from the
// table above (see v512_gelu for the form; beyond |x| = 6, h is taken as 0). M gives the
// lookup: table8_index(t + 1.5 * 2^23) (the rounded t is in the low mantissa bits) and
// table8_lookup(row, index); and abs, keep_if_less(v, a, b) (v where a < b, else +0) and
// select_negative(x, a, b) (a where the sign bit of x is set, else b).
template <class M>
inline typename M::V vec_gelu_table8(typename M::V x) {
  using V = typename M::V;
  const V a = M::abs(x);
  V t = M::fma(a, M::set1(8.0f / 6.0f), M::set1(-0.5f));
  // t first: a NaN t may become 7.49999952 (AVX2's minps) or stay NaN (NEON); x * phi is
  // NaN either way.
  t = M::min(t, M::set1(7.49999952f));
  const V magic = M::set1(12582912.0f);
  const V rounded = M::add(t, magic);
  const typename M::Table8Index idx = M::table8_index(rounded);
  const V u = M::sub(t, M::sub(rounded, magic));
  V h = M::table8_lookup(kGeluTable8[6], idx);
  for (int j = 5; j >= 0; --j) h = M::fma(h, u, M::table8_lookup(kGeluTable8[j], idx));
  h = M::keep_if_less(h, a, M::set1(6.0f));
  const V phi = M::select_negative(x, h, M::sub(M::set1(1.0f), h));
  return M::mul(x, phi);
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
