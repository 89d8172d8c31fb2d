// NEON element-wise math shared by the activation and GEMM-epilogue kernels, so both
// produce the same bits. Include only from nn/arch/arm/*.cpp.
// The same algorithms, coefficients and operation order as nn/arch/x86/vecmath_avx2.h
// (exp clamped to |x| <= 100, 2^n from the exponent field; GELU from the 8-interval
// table with a degree-6 polynomial), so the results are those of the AVX2 kernels up to
// NaN payloads; the table lookup that AVX2 does with vpermps is one vqtbl2q (two 16-byte
// table registers hold a row of 8 floats) per coefficient.
// NaN: vminq/vmaxq return NaN when either operand is NaN, so NaN passes every clamp.
#pragma once

#include <arm_neon.h>

#include <cstdint>

#include "nn/act.h"
#include "nn/arch/arm/vecops_neon.h"
#include "nn/vecmath_act.h"

namespace nn {
namespace {

// h(a) = Phi(-a) on [0, 6): 8 intervals of width 3/4, a degree-6 polynomial in
// u = a * 4/3 - 0.5 - i per interval i: the table of nn/arch/x86/vecmath_avx2.h.
alignas(16) constexpr float kGeluTable8[7][8] = {
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

// Entry `bytes` (4 byte indices per lane) of table row j.
inline float32x4_t gelu_coeff(int j, uint8x16_t bytes) {
  const uint8_t* row = reinterpret_cast<const uint8_t*>(kGeluTable8[j]);
  const uint8x16x2_t tab = {{vld1q_u8(row), vld1q_u8(row + 16)}};
  return vreinterpretq_f32_u8(vqtbl2q_u8(tab, bytes));
}

// gelu(x) = x * Phi(x); see v512_gelu in nn/arch/x86/vecmath_avx512.h.
inline float32x4_t vq_gelu(float32x4_t x) {
  const float32x4_t a = vabsq_f32(x);
  float32x4_t t = vfmaq_f32(vdupq_n_f32(-0.5f), a, vdupq_n_f32(8.0f / 6.0f));
  t = vminq_f32(t, vdupq_n_f32(7.49999952f));
  // Adding 1.5 * 2^23 rounds t to an integer held in the low mantissa bits.
  const float32x4_t magic = vdupq_n_f32(12582912.0f);
  const float32x4_t rounded = vaddq_f32(t, magic);
  const uint32x4_t idx = vandq_u32(vreinterpretq_u32_f32(rounded), vdupq_n_u32(7));
  const float32x4_t u = vsubq_f32(t, vsubq_f32(rounded, magic));
  // Lane i's float i spans bytes 4 idx .. 4 idx + 3 of the 32-byte row.
  const uint8x16_t bytes = vreinterpretq_u8_u32(
      vaddq_u32(vmulq_n_u32(idx, 0x04040404u), vdupq_n_u32(0x03020100u)));
  float32x4_t h = gelu_coeff(6, bytes);
  for (int j = 5; j >= 0; --j) h = vfmaq_f32(gelu_coeff(j, bytes), h, u);
  h = vreinterpretq_f32_u32(
      vandq_u32(vreinterpretq_u32_f32(h), vcltq_f32(a, vdupq_n_f32(6.0f))));
  const float32x4_t one_minus_h = vsubq_f32(vdupq_n_f32(1.0f), h);
  // Phi(x) = h(|x|) where the sign bit of x is set (AVX2's blendv on x).
  const uint32x4_t negative =
      vreinterpretq_u32_s32(vshrq_n_s32(vreinterpretq_s32_f32(x), 31));
  const float32x4_t phi = vbslq_f32(negative, h, one_minus_h);
  return vmulq_f32(x, phi);
}

// x < 0 ? 0 : x, like torch.relu: keeps NaN and -0.
inline float32x4_t vq_relu(float32x4_t x) {
  return vreinterpretq_f32_u32(vbicq_u32(vreinterpretq_u32_f32(x), vcltzq_f32(x)));
}

// The NEON vector ops with this file's GELU, ReLU and exp steps: the trait of the kernels
// written once over a vector type that apply an activation (nn/vecmath_act.h builds the
// others from these; nn/activation_loop.h, nn/gemm_tile_frame.h).
struct MathOpsNeon : VecOpsNeon {
  // exp (nn/vecmath_act.h), as on AVX2: 2^n from the exponent field, n clamped to
  // [-127, 128] (underflow to zero, overflow to infinity). nc is integral, so the
  // truncating conversion is exact.
  static constexpr float kExpClamp = 100.0f;
  static V times_pow2(V p, V n) {
    const float32x4_t nc = vminq_f32(vmaxq_f32(n, vdupq_n_f32(-127.0f)), vdupq_n_f32(128.0f));
    const int32x4_t bits = vshlq_n_s32(vaddq_s32(vcvtq_s32_f32(nc), vdupq_n_s32(127)), 23);
    return vmulq_f32(p, vreinterpretq_f32_s32(bits));
  }
  static V gelu(V x) { return vq_gelu(x); }
  static V relu(V x) { return vq_relu(x); }
  template <Act ACT>
  static V act(V x) { return vec_act<MathOpsNeon, ACT>(x); }
};

}  // namespace
}  // namespace nn
