// NEON element-wise math shared by the activation and GEMM-epilogue kernels, so both
// produce the same bits. Include only from nn/arch/arm/*.cpp.
// The same algorithms, coefficients and operation order as nn/arch/x86/vecmath_avx2.h
// (exp clamped to |x| <= 100, 2^n from the exponent field; the 8-interval GELU of
// nn/vecmath_act.h), so the results are those of the AVX2 kernels up to NaN payloads; the
// table lookup that AVX2 does with vpermps is one vqtbl2q per coefficient.
// NaN: vminq/vmaxq return NaN when either operand is NaN, so NaN passes every clamp.
#pragma once

#include <arm_neon.h>

#include <cstdint>

#include "nn/act.h"
#include "nn/arch/arm/vecops_neon.h"
#include "nn/vecmath_act.h"

namespace nn {
namespace {

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
  // The GELU of nn/vecmath_act.h from the 8-interval table: a lane's index is the low three
  // bits of t + 1.5 * 2^23, and its float spans bytes 4 i .. 4 i + 3 of the 32-byte row,
  // which one vqtbl2q (two 16-byte table registers) reads per coefficient.
  using Table8Index = uint8x16_t;
  static Table8Index table8_index(V rounded) {
    const uint32x4_t i = vandq_u32(vreinterpretq_u32_f32(rounded), vdupq_n_u32(7));
    return vreinterpretq_u8_u32(vaddq_u32(vmulq_n_u32(i, 0x04040404u), vdupq_n_u32(0x03020100u)));
  }
  static V table8_lookup(const float* row, Table8Index bytes) {
    const uint8_t* r = reinterpret_cast<const uint8_t*>(row);
    const uint8x16x2_t tab = {{vld1q_u8(r), vld1q_u8(r + 16)}};
    return vreinterpretq_f32_u8(vqtbl2q_u8(tab, bytes));
  }
  static V abs(V a) { return vabsq_f32(a); }
  static V keep_if_less(V v, V a, V b) {
    return vreinterpretq_f32_u32(vandq_u32(vreinterpretq_u32_f32(v), vcltq_f32(a, b)));
  }
  // The sign bit of x spread over its lane selects, like AVX2's blendv on x.
  static V select_negative(V x, V if_neg, V otherwise) {
    const uint32x4_t negative = vreinterpretq_u32_s32(vshrq_n_s32(vreinterpretq_s32_f32(x), 31));
    return vbslq_f32(negative, if_neg, otherwise);
  }
  static V gelu(V x) { return vec_gelu_table8<MathOpsNeon>(x); }
  static V relu(V x) { return vq_relu(x); }
  template <Act ACT>
  static V act(V x) { return vec_act<MathOpsNeon, ACT>(x); }
};

}  // namespace
}  // namespace nn
