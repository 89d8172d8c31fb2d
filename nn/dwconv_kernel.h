// Interface between nn/dwconv.cpp (validation, packing, threading) and the ISA kernels
// (nn/dwconv_block.h, instantiated in nn/arch/*/dwconv_*.cpp). Plain data and
// declarations only: the ISA files include it, so it must not define inline functions or
// templates.
#pragma once

#include <cstddef>

namespace nn {

// One depthwise convolution call. Taps are packed [c/L][kh][kw][L] (L = 16 for
// AVX-512, 8 for AVX2, 4 for NEON, zero-padded channel tail); bias is [c rounded up to
// L], zeros where the layer has none.
struct DwConvJob {
  const float* in = nullptr;  // NHWC [n, h, w, c]
  float* out = nullptr;       // NHWC [n, oh, ow, c]
  const float* taps = nullptr;
  const float* bias = nullptr;
  int h = 0, w = 0, c = 0;
  int oh = 0, ow = 0;
  int kh = 0, kw = 0, stride_h = 1, stride_w = 1, pad_h = 0, pad_w = 0;
  int act = 0;  // static_cast<int>(nn::Act): None, Relu or HardSwish
  // Output row oy of image n starts at out + n * out_image + (oy - out_row0) * ow * c:
  // the whole tensor (out_image = oh * ow * c, out_row0 = 0) or a band of one image's rows.
  std::ptrdiff_t out_image = 0;
  int out_row0 = 0;
};

// Largest kh * kw the kernels accept: one tile's zero-padded input rows live in a
// fixed stack buffer of at least kh * kw * L floats (64 KiB for AVX-512).
constexpr int kDwConvMaxTaps = 1024;
constexpr int kDwConvMaxKernel = 32;

// Target size of one channel block's ring of padded input rows (kept in L1).
constexpr int kDwConvRingTargetBytes = 32 * 1024;

// Computes output rows [oy0, oy1) of image `n` for channel blocks [cb0, cb1) (block
// cb covers channels [cb*L, cb*L+L) clipped to c). Each output element is summed in
// the fixed order ky, kx ascending, so the split into calls never changes a result.
using DwConvBlockFn = void (*)(const DwConvJob& job, int n, int cb0, int cb1, int oy0, int oy1);
void dwconv_block_neon(const DwConvJob& job, int n, int cb0, int cb1, int oy0, int oy1);
void dwconv_block_avx512(const DwConvJob& job, int n, int cb0, int cb1, int oy0, int oy1);
void dwconv_block_avx2(const DwConvJob& job, int n, int cb0, int cb1, int oy0, int oy1);

}  // namespace nn
