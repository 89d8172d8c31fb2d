// The NEON "vector ops" of the kernels written once over a vector type
// (nn/dwconv_block.h, nn/layernorm_rows.h, nn/resize_row.h): 4 floats per q register.
// Advanced SIMD is baseline on aarch64, so no flags are needed. The same interface as
// nn/arch/x86/vecops_avx2.h and nn/arch/x86/vecops_avx512.h, less broadcast, which only
// the x86 GEMM K loop uses (the NEON one multiplies by a scalar lane, vfmaq_n_f32).
#pragma once

#include <arm_neon.h>

#include <cstring>

namespace nn {
namespace {

struct VecOpsNeon {
  using V = float32x4_t;
  using Mask = int;  // lanes [0, n); NEON has no masked loads
  using V4 = float32x4_t;  // one float per row of a group of four; GCC operators apply
  static constexpr int kLanes = 4;

  static V zero() { return vdupq_n_f32(0.0f); }
  static V set1(float x) { return vdupq_n_f32(x); }
  static V load(const float* p) { return vld1q_f32(p); }
  static V loadu(const float* p) { return vld1q_f32(p); }
  static void store(float* p, V v) { vst1q_f32(p, v); }
  static void storeu(float* p, V v) { vst1q_f32(p, v); }
  static Mask mask(int n) { return n; }
  // Lanes outside the mask: not read, loaded as zero; not written.
  static V load_part(const float* p, Mask n) {
    float t[4] = {0.0f, 0.0f, 0.0f, 0.0f};
    std::memcpy(t, p, static_cast<std::size_t>(n) * sizeof(float));
    return vld1q_f32(t);
  }
  static void store_part(float* p, Mask n, V v) {
    float t[4];
    vst1q_f32(t, v);
    std::memcpy(p, t, static_cast<std::size_t>(n) * sizeof(float));
  }
  static V keep(Mask n, V v) {
    static const uint32_t kIndex[4] = {0, 1, 2, 3};
    const uint32x4_t m = vcltq_u32(vld1q_u32(kIndex), vdupq_n_u32(static_cast<uint32_t>(n)));
    return vreinterpretq_f32_u32(vandq_u32(m, vreinterpretq_u32_f32(v)));
  }
  static V add(V a, V b) { return vaddq_f32(a, b); }
  static V sub(V a, V b) { return vsubq_f32(a, b); }
  static V mul(V a, V b) { return vmulq_f32(a, b); }
  static V div(V a, V b) { return vdivq_f32(a, b); }
  static V fma(V a, V b, V c) { return vfmaq_f32(c, a, b); }  // a * b + c, one rounding
  static V fnma(V a, V b, V c) { return vfmsq_f32(c, a, b); }  // c - a * b, one rounding
  static V round_nearest(V a) { return vrndnq_f32(a); }  // to the nearest integer, ties to even
  // fmax/fmin return NaN when either operand is NaN, so NaN propagates as in torch.
  static V max(V a, V b) { return vmaxq_f32(a, b); }
  static V min(V a, V b) { return vminq_f32(a, b); }

  static V4 sqrt4(V4 v) { return vsqrtq_f32(v); }
  static V4 max4(V4 a, V4 b) { return vmaxq_f32(a, b); }

  // Lane k = sum of the lanes of the k-th vector, folded by halves (lane i + lane i + 2,
  // then the two partials), the order of the x86 folds.
  static V4 fold4(V a, V b, V c, V d) {
    const V ab = vaddq_f32(vcombine_f32(vget_low_f32(a), vget_low_f32(b)),
                           vcombine_f32(vget_high_f32(a), vget_high_f32(b)));
    const V cd = vaddq_f32(vcombine_f32(vget_low_f32(c), vget_low_f32(d)),
                           vcombine_f32(vget_high_f32(c), vget_high_f32(d)));
    // ab = [a0+a2, a1+a3, b0+b2, b1+b3]; pairwise adds finish each row.
    return vpaddq_f32(ab, cd);
  }
};

}  // namespace
}  // namespace nn
