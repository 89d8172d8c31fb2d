// Dense 2-D convolution (groups = 1) on NHWC tensors: 1x1 stride-1 layers as one
// GEMM on the input rows in place, 3x3 stride-1 pad-1 layers (with at least
// kWinogradMinChannels channels in and out) by Winograd F(4x4, 3x3) (nn/winograd.h),
// everything else as im2col over blocks of output rows followed by the packed GEMM.
// Depthwise convolutions use nn/dwconv.h. Zero padding, PyTorch's output size rule.
#pragma once

#include <cstddef>

#include "nn/act.h"
#include "nn/buffer.h"
#include "nn/gemm.h"
#include "nn/tensor.h"
#include "nn/winograd.h"

namespace nn {

struct Conv2dParams {
  int cin = 0, cout = 0;
  int kh = 1, kw = 1;
  int stride_h = 1, stride_w = 1;
  int pad_h = 0, pad_w = 0;
  int groups = 1;  // the reference handles any; Conv2dWeights requires 1
};

class Conv2dWeights {
 public:
  Conv2dWeights() = default;
  // w: PyTorch [cout, cin, kh, kw]; bias: [cout] or null. Repacks once, for Winograd
  // when the layer qualifies and winograd_enabled(), else for the direct GEMM.
  static Conv2dWeights pack(const float* w, const float* bias, const Conv2dParams& p,
                            Isa isa = active_isa());
  const Conv2dParams& params() const { return p_; }
  // The direct form's GEMM weights (empty when is_winograd()).
  const GemmWeights& gemm() const { return gemm_; }
  bool is_winograd() const { return !winograd_.empty(); }
  const WinogradWeights& winograd() const { return winograd_; }
  std::size_t weight_bytes() const { return gemm_.bytes() + winograd_.bytes(); }
  const float* bias() const { return bias_.empty() ? nullptr : bias_.data(); }
  // A 1x1, stride-1, unpadded convolution reads its input rows in place (no im2col).
  bool is_pointwise() const;

 private:
  Conv2dParams p_;
  GemmWeights gemm_;
  WinogradWeights winograd_;
  AlignedBuffer bias_;
};

Shape conv2d_output_shape(const Shape& in, const Conv2dParams& p);

// Whether a layer with these parameters qualifies for Winograd F(4x4, 3x3).
bool conv2d_winograd_applies(const Conv2dParams& p);

// Output rows one matrix product covers: enough rows of width out_w for about
// kConvBlockPixels pixels, so narrow deep layers do not stream their whole weight
// matrix from L3 for a few dozen pixels.
constexpr int kConvBlockPixels = 128;
int conv2d_block_rows(int out_w);

// Floats of scratch one thread of conv2d() needs for these weights and an output
// width out_w (im2col rows of one block, or one block of Winograd tiles).
std::size_t conv2d_scratch_floats(const Conv2dWeights& w, int out_w);

// Output rows [y0, y1) of image n, single-threaded, in blocks of
// conv2d_block_rows(out.shape.w) rows (direct weights only: a Winograd tile spans four
// rows). `residual` (same shape as out, may alias it) is added per nn/gemm.h's
// epilogue order; act_after_residual likewise.
void conv2d_rows(const ConstTensorView& in, const Conv2dWeights& w, const TensorView& out, int n,
                 int y0, int y1, float* scratch, Act act = Act::None,
                 const float* residual = nullptr, bool act_after_residual = false);

// All rows, split over the team's threads. scratch holds num_threads() *
// conv2d_scratch_floats(w, out.shape.w) floats (the caller plans it once).
void conv2d(const ConstTensorView& in, const Conv2dWeights& w, const TensorView& out,
            float* scratch, Act act = Act::None, const float* residual = nullptr,
            bool act_after_residual = false);

// Scalar reference on PyTorch-layout weights, any groups.
void conv2d_ref(const ConstTensorView& in, const float* w, const float* bias,
                const Conv2dParams& p, const TensorView& out, Act act = Act::None);

}  // namespace nn
