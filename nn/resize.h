// Resampling NHWC tensors to the height and width of `out`, with the index and
// weight arithmetic of PyTorch 1.13's F.interpolate on CPU.
//
// scale_h / scale_w are the scale_factor given to F.interpolate (used when
// recompute_scale_factor is not True); 0 means the sizes alone decide, i.e.
// F.interpolate(x, size=(out_h, out_w)). With a factor PyTorch uses 1/factor
// instead of in/out, which differs for factors that are not exact.
#pragma once

#include "nn/tensor.h"

namespace nn {

// mode='nearest': src = min(floor(dst * s), in - 1) in float with s = float(in) / out
// (or float(1 / scale)); out == in copies and out == 2 in takes dst / 2.
void upsample_nearest(const ConstTensorView& in, const TensorView& out, double scale_h = 0.0,
                      double scale_w = 0.0);

// mode='bilinear', align_corners=False, antialias=False. Per axis:
// src = max(s * (dst + 0.5) - 0.5, 0) in double, i0 = floor(src), i1 = min(i0 + 1, in - 1),
// l1 = float(src - i0), l0 = 1 - l1 (out == in: copy). Then, as PyTorch's NCHW
// kernel rounds it on this machine:
//   t0 = fma(x[i0][j0], w0, x[i0][j1] * w1), t1 = fma(x[i1][j0], w0, x[i1][j1] * w1),
//   y = fma(t0, h0, t1 * h1),
// which matches torch 1.13's output for NCHW tensors with C > 1 bitwise (checked on
// 60 random size pairs). PyTorch treats a C == 1 tensor as channels-last and runs
// another kernel (four weighted terms); there the results differ by up to ~1.3e-7
// of max|x|.
void resize_bilinear(const ConstTensorView& in, const TensorView& out, double scale_h = 0.0,
                     double scale_w = 0.0);

}  // namespace nn
