// Depthwise convolution (groups == in channels == out channels) on NHWC tensors:
// ConvNeXt's 7x7 (stride 1, pad 3), the StixelNExT++ V4 head's 1x5 (pad 0,2) and
// MobileNetV3's 3x3 / 5x5 with stride 1 or 2. Zero padding, PyTorch's output size
// rule: out = (in + 2 pad - k) / stride + 1.
//
// Limits: kernel sides 1..32, stride 1..64, padding 0..4096. Each output element is
// sum over ky, then kx (ascending) of x * w, starting from zero, then + bias, then
// the activation; the AVX2 / AVX-512 kernels use one FMA per tap in that order (the
// scalar path separate multiply and add, bitwise equal to dwconv_ref).
#pragma once

#include "nn/act.h"
#include "nn/buffer.h"
#include "nn/isa.h"
#include "nn/tensor.h"

namespace nn {

struct DwConvParams {
  int kh = 7, kw = 7;
  int stride_h = 1, stride_w = 1;
  int pad_h = 3, pad_w = 3;
  Act act = Act::None;  // applied after the bias
};

// Weights repacked once at load: AVX-512 [c/16][kh][kw][16], AVX2 [c/8][kh][kw][8]
// (channel tail zero-padded), scalar [kh][kw][c]. Only Act::None, Relu and HardSwish
// are fused; pack throws nn::Error for the others (apply them with nn/activation.h).
class DwConvWeights {
 public:
  DwConvWeights() = default;
  // w: PyTorch [c, 1, kh, kw]; bias: [c] or null. `isa` is clamped to what the CPU
  // supports; dwconv() then runs that ISA's kernel whatever the active ISA is.
  static DwConvWeights pack(const float* w, const float* bias, int c, const DwConvParams& p,
                            Isa isa = active_isa());
  int channels() const { return c_; }
  const DwConvParams& params() const { return p_; }
  Isa isa() const { return isa_; }
  const float* taps() const { return taps_.data(); }
  const float* bias() const { return bias_.data(); }

 private:
  AlignedBuffer taps_, bias_;
  int c_ = 0;
  DwConvParams p_;
  Isa isa_ = Isa::Scalar;
};

Shape dwconv_output_shape(const Shape& in, const DwConvParams& p);

// out must have dwconv_output_shape(in.shape, p); out must not alias in.
// Parallel over output rows inside; bitwise identical for any thread count.
void dwconv(const ConstTensorView& in, const DwConvWeights& w, const TensorView& out);

// Output rows [oy0, oy1) of image n of dwconv(in, w) into out, dense [oy1 - oy0][ow][c],
// on the calling thread: bitwise the elements dwconv() writes for those rows. For callers
// that consume a band of rows while it is in cache (ConvNeXt's blocks). out must not
// alias in.
void dwconv_rows(const ConstTensorView& in, const DwConvWeights& w, int n, int oy0, int oy1,
                 float* out);

// Scalar reference on unpacked PyTorch weights [c, 1, kh, kw].
void dwconv_ref(const ConstTensorView& in, const float* w, const float* bias,
                const DwConvParams& p, const TensorView& out);

}  // namespace nn
