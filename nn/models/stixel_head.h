// The StixelNExT++ heads that trained checkpoints exist for (reference
// stixelnext.md §1.3), on the row-pooled backbone features F = [n, 1, W', C]:
//
//   V4 (latest)  F + pw(GELU(dw1x5(F))) -> 1x1 C->256 -> up -> LN -> [geometry|depth|prob] 1x1 + sigmoid
//                output [n, 4, 64, U] = vB, vT, depth residual, P
//   V1 / V3      [ColumnAttention(F) (local +-1 / global), F] -> 1x1 2C->192 -> up -> LN -> sigmoid
//   V0 / V2      1x1 C->192 -> up -> LN -> sigmoid (V2 carries unused attention tensors)
//                output [n, 3, 64, U] = vB, vT, P
//
// Channel c of the head output is attribute c / 64, candidate c % 64. Everything
// after the nearest upsampling is per column, so W' columns are computed and each
// output column u copies source column floor(u * W' / U) (bitwise what PyTorch gets).
#pragma once

#include <string>
#include <vector>

#include "nn/buffer.h"
#include "nn/dump.h"
#include "nn/dwconv.h"
#include "nn/gemm.h"
#include "nn/tensor.h"
#include "weights/safetensors.h"
#include "weights/tensor_spec.h"

namespace nn {

enum class StixelHeadVariant { V0, V1, V2, V3, V4 };

const char* stixel_head_name(StixelHeadVariant v);  // "v4", ...
bool parse_stixel_head(const std::string& text, StixelHeadVariant* out);

// Tells the variant from the tensor names and shapes under `prefix` ("classifier."):
// local_mixing.* -> V4; channel_reduce with 2C inputs -> V1 (V3 has the same tensors:
// force it); C inputs with attention tensors -> V2; a lone 1x1 conv + norm -> V0.
// Throws weights::Error listing what each layout expects when nothing fits.
StixelHeadVariant detect_stixel_head(const weights::SafeTensors& st, const std::string& prefix,
                                     int in_channels);

// The tensors of a head variant under `prefix` for C backbone channels. V0's two
// layers have no fixed names: `reduce` and `norm` name them (default: the
// attention-free StixelHead's "channel_reduce" and "up.1").
std::vector<weights::TensorSpec> stixel_head_tensor_specs(StixelHeadVariant variant, int in_channels,
                                                          const std::string& prefix,
                                                          const std::string& reduce = "channel_reduce",
                                                          const std::string& norm = "up.1");

class StixelHead {
 public:
  static constexpr int kCandidates = 64;

  StixelHead(const weights::SafeTensors& st, const std::string& prefix, StixelHeadVariant variant,
             int in_channels);

  // Every tensor this head reads (names and shapes).
  const std::vector<weights::TensorSpec>& tensor_specs() const { return specs_; }
  StixelHeadVariant variant() const { return variant_; }
  int attributes() const { return variant_ == StixelHeadVariant::V4 ? 4 : 3; }
  std::size_t weight_bytes() const;

  // Plans scratch for n images of W' feature columns.
  void plan(int n, int feature_columns);
  // pooled: [n, 1, W', C] NHWC. out: [n, attributes, 64, columns] (PyTorch layout),
  // after the sigmoid. Allocates nothing.
  void forward(const ConstTensorView& pooled, int columns, float* out);

  // Intermediate tensors under the PyTorch head's module names (prefix "classifier."):
  // V4 local_mixing.depthwise, local_mixing.pointwise, local_mixing, shared_reduce, up.0,
  // up.1, up; V1/V3 the attention's
  // query/key/value layers and attention_layer; channel_reduce (V0: its own name),
  // up.0, up.1, up. Null: off. The head's output itself is dumped by the model.
  void set_dump(DumpSink* sink) { dump_ = sink; }
  // What the head's output tensor stands for where the engine fused modules ("" if none).
  const std::string& output_covers() const { return output_covers_; }
  // What the head computes apart for a dump ("" if nothing): dump.path's part.
  std::string dump_path() const;

 private:
  // rows [n * w, k] (NHWC, one feature row) as PyTorch's [n, k, 1, columns] after the
  // nearest upsampling to `columns`.
  void dump_reduced(int n, int w, int columns, bool normalised) const;
  void dump_upsampled(const std::string& name, const float* rows, int n, int w, int k, int columns) const;
  // Channels [c0, c0 + k) of rows with stride ld, as [n, w, k] (a Linear's output) or,
  // when as_nchw, as [n, k, 1, w].
  void dump_columns(const std::string& name, const float* rows, int n, int w, int ld, int c0, int k,
                    bool as_nchw) const;

  // V4: local_mixing's output, pointwise(GELU(depthwise(x))) from a_, which forward()
  // fuses with the residual x into one product; computed again without it, for the dump.
  void dump_local_mixing(int n, int w);
  void attention(const float* x, int n, int w, float* att) const;

  StixelHeadVariant variant_;
  int c_ = 0, reduced_ = 0;
  std::vector<weights::TensorSpec> specs_;
  // V4
  DwConvWeights mix_dw_;
  GemmWeights mix_pw_, heads_;
  AlignedBuffer mix_pw_bias_, heads_bias_;
  // V1/V3: q, k, v stacked into one [3C x C] product.
  GemmWeights qkv_;
  AlignedBuffer qkv_bias_;
  // all
  GemmWeights reduce_;
  AlignedBuffer reduce_bias_, ln_gamma_, ln_beta_;
  // scratch
  AlignedBuffer a_, b_, c_buf_;
  std::vector<float> dump_mix_;  // grown only while dumping (dump_local_mixing)
  int planned_n_ = 0, planned_w_ = 0;
  DumpSink* dump_ = nullptr;
  std::string name_dw_, name_pw_, name_mix_, name_reduce_, name_up0_, name_norm_, name_up_, name_att_, name_q_, name_k_, name_v_;
  std::string output_covers_;
};

}  // namespace nn
