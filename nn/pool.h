// Pooling on NHWC tensors with PyTorch's arithmetic.
#pragma once

#include "nn/tensor.h"

namespace nn {

// StixelNExT++'s AvgPool2d((H, 1)): out[n][0][x][ch] = (in[n][0][x][ch] + ... +
// in[n][h-1][x][ch]) / h, a float sum in row order and one float division, which is
// what torch.nn.functional.avg_pool2d computes (bitwise). Output shape {n, 1, w, c}.
Shape mean_over_rows_shape(const Shape& in);
void mean_over_rows(const ConstTensorView& in, const TensorView& out);

// torch.nn.functional.max_pool2d(x, (kh, kw), (stride_h, stride_w), (pad_h, pad_w)),
// dilation 1, ceil_mode=False. Padding acts as -inf and, as in PyTorch, may be at
// most half the kernel; a NaN in a window makes that output NaN.
struct MaxPoolParams {
  int kh = 3, kw = 3;
  int stride_h = 2, stride_w = 2;
  int pad_h = 1, pad_w = 1;
};
// PyTorch's size rule: out = (in + 2 pad - k) / stride + 1.
Shape max_pool2d_output_shape(const Shape& in, const MaxPoolParams& p);
void max_pool2d(const ConstTensorView& in, const MaxPoolParams& p, const TensorView& out);

// Mean over the h*w pixels per channel (MobileNetV3 squeeze-excitation's
// adaptive_avg_pool2d(x, 1)); accumulated in double, so within half an ulp of the
// exact mean. Output shape {n, 1, 1, c}.
Shape global_avg_pool_shape(const Shape& in);
void global_avg_pool(const ConstTensorView& in, const TensorView& out);

}  // namespace nn
