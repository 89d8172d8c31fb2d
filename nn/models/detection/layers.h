// Loading helpers shared by the detector's parts: convolutions with frozen batch
// norm folded in at load (y = x * s + (beta - mean * s), s = gamma / sqrt(var + eps)),
// plain convolutions with bias, and NHWC activation buffers planned once.
#pragma once

#include <string>
#include <vector>

#include "nn/act.h"
#include "nn/buffer.h"
#include "nn/conv2d.h"
#include "nn/dwconv.h"
#include "nn/profiler.h"
#include "nn/tensor.h"
#include "weights/safetensors.h"
#include "weights/tensor_spec.h"

namespace nn::detection {

using Dims = std::vector<std::int64_t>;

// Whose module names (and, where they differ, whose layer choices) a detector part
// follows: torchvision's state_dict or detectron2's checkpoint.
enum class WeightLayout { Torchvision, Detectron2 };

// An owned NHWC activation sized at plan time.
struct Activation {
  AlignedBuffer data;
  Shape shape;
  void resize(const Shape& s) {
    if (data.size() < s.count()) data.resize(s.count());
    shape = s;
  }
  TensorView view() { return {data.data(), shape}; }
  ConstTensorView cview() const { return {data.data(), shape}; }
};

// Specs of a conv weight [cout, cin, kh, kw] and, under bn_prefix, a batch norm.
void add_conv_bn_specs(std::vector<weights::TensorSpec>& specs, const std::string& conv_weight,
                       const std::string& bn_prefix, const Dims& weight_shape);

// Conv (no bias) + batch norm folded; p describes the convolution.
Conv2dWeights load_conv_bn(const weights::SafeTensors& st, const std::string& conv_weight,
                           const std::string& bn_prefix, const Conv2dParams& p, float eps);
DwConvWeights load_dwconv_bn(const weights::SafeTensors& st, const std::string& conv_weight,
                             const std::string& bn_prefix, int channels, const DwConvParams& p, float eps);
// Conv with its own bias: `prefix` + "weight" / "bias".
Conv2dWeights load_conv(const weights::SafeTensors& st, const std::string& prefix, const Conv2dParams& p);

// A profiler row for a convolution producing `out` ("conv 3x3/2", "conv 3x3 winograd"),
// counting the direct form's multiply-adds; -1 when prof is null.
int add_conv_row(Profiler* prof, const std::string& layer, const Conv2dWeights& w, const Shape& out);

// conv2d() timed into profiler row `row` (prof may be null, row then -1).
void conv2d_timed(Profiler* prof, int row, const ConstTensorView& in, const Conv2dWeights& w, const TensorView& out,
                  float* scratch, Act act = Act::None, const float* residual = nullptr,
                  bool act_after_residual = false);

// Thread-shared im2col scratch for every conv2d of a model, sized by the largest need.
class ConvScratch {
 public:
  void require(const Conv2dWeights& w, int out_w);
  void allocate();
  float* get();  // re-sizes if the thread count grew since planning
 private:
  std::size_t per_thread_ = 0;
  int threads_ = 0;
  AlignedBuffer buf_;
};

}  // namespace nn::detection
