// Dense 2-D convolution (groups = 1) on NHWC tensors, as im2col over one output row
// at a time followed by the packed GEMM: ConvNeXt's 4x4/4 stem and 2x2/2
// downsampling, the detector's 1x1 / 3x3 / 7x7 convolutions. Depthwise convolutions
// use nn/dwconv.h. Zero padding, PyTorch's output size rule.
#pragma once

#include <cstddef>

#include "nn/act.h"
#include "nn/buffer.h"
#include "nn/gemm.h"
#include "nn/tensor.h"

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
  // w: PyTorch [cout, cin, kh, kw]; bias: [cout] or null. Repacks once.
  static Conv2dWeights pack(const float* w, const float* bias, const Conv2dParams& p,
                            Isa isa = active_isa());
  const Conv2dParams& params() const { return p_; }
  const GemmWeights& gemm() const { return gemm_; }
  const float* bias() const { return bias_.empty() ? nullptr : bias_.data(); }
  // A 1x1, stride-1, unpadded convolution reads its input rows in place (no im2col).
  bool is_pointwise() const;

 private:
  Conv2dParams p_;
  GemmWeights gemm_;
  AlignedBuffer bias_;
};

Shape conv2d_output_shape(const Shape& in, const Conv2dParams& p);

// Output rows one matrix product covers: enough rows of width out_w for about
// kConvBlockPixels pixels, so narrow deep layers do not stream their whole weight
// matrix from L3 for a few dozen pixels.
constexpr int kConvBlockPixels = 128;
int conv2d_block_rows(int out_w);

// Floats of scratch one thread needs for one block of conv2d_block_rows(out_w)
// output rows of width out_w.
std::size_t conv2d_scratch_floats(const Conv2dParams& p, int out_w);

// Output rows [y0, y1) of image n, single-threaded, in blocks of
// conv2d_block_rows(out.shape.w) rows. `residual` (same shape as out,
// may alias it) is added per nn/gemm.h's epilogue order; act_after_residual likewise.
void conv2d_rows(const ConstTensorView& in, const Conv2dWeights& w, const TensorView& out, int n,
                 int y0, int y1, float* scratch, Act act = Act::None,
                 const float* residual = nullptr, bool act_after_residual = false);

// All rows, split over the OpenMP team. scratch holds num_threads() *
// conv2d_scratch_floats(p, out.shape.w) floats (the caller plans it once).
void conv2d(const ConstTensorView& in, const Conv2dWeights& w, const TensorView& out,
            float* scratch, Act act = Act::None, const float* residual = nullptr,
            bool act_after_residual = false);

// Scalar reference on PyTorch-layout weights, any groups.
void conv2d_ref(const ConstTensorView& in, const float* w, const float* bias,
                const Conv2dParams& p, const TensorView& out, Act act = Act::None);

}  // namespace nn
