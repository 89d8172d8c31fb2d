// torchvision's MobileNetV3-Large feature extractor as the detection models build
// it (width 1.0, no dilation, full tail; batch norm folded at load), returning the
// two FPN inputs: features[13] (after its stride-2 depthwise stage) and features[16].
#pragma once

#include <string>
#include <memory>
#include <vector>

#include "nn/models/detection/backbone.h"
#include "nn/models/detection/layers.h"

namespace nn::detection {

class MobileNetV3Backbone : public Backbone {
 public:
  // prefix: "backbone.body."; eps: the frozen batch norms' epsilon.
  MobileNetV3Backbone(const weights::SafeTensors& st, const std::string& prefix, float eps = 1e-5f);

  static std::vector<weights::TensorSpec> tensor_specs(const std::string& prefix);
  std::vector<int> out_channels() const override { return {160, 960}; }

  std::unique_ptr<Backbone> clone() const override { return std::make_unique<MobileNetV3Backbone>(*this); }
  void plan(int h, int w, Profiler* layers) override;
  // in: {1, h, w, 3}. Returns views of the two outputs (valid until the next call).
  const std::vector<ConstTensorView>& forward(const ConstTensorView& in) override;
  // backbone.body.0 (stem), per InvertedResidual backbone.body.i and its block.0
  // (expand), block.1 (depthwise), block.2 (squeeze-excitation) and, without a
  // residual, block.3 (project); backbone.body.16.
  void set_dump(DumpSink* sink) override { dump_ = sink; }

 private:
  std::string prefix_;  // "backbone.body."; profile rows use torchvision's module names
  struct Block {
    int cin = 0, exp = 0, cout = 0, k = 3, stride = 1, se = 0;
    Act act = Act::Relu;
    bool has_expand = false, residual = false;
    Conv2dWeights expand, project;
    DwConvWeights dw;
    GemmWeights fc1, fc2;
    AlignedBuffer fc1_bias, fc2_bias;
    Shape a, b, out;  // planned outputs of expand, depthwise, project
    Activation pooled, squeezed, excited;
    int row_expand = -1, row_dw = -1, row_se = -1, row_project = -1;  // profiler rows
    // torchvision's names: the InvertedResidual "backbone.body.i" and its block parts.
    std::string name, expand_name, dw_name, se_name, project_name;
  };
  void run_block(Block& blk, const ConstTensorView& in, const TensorView& out);

  Conv2dWeights stem_, last_;
  std::vector<Block> blocks_;
  Shape stem_shape_;
  // Expand and depthwise outputs live only inside a block: one buffer each for all
  // blocks. Block outputs alternate between two buffers (the first also holds the
  // stem output); block 13's output, which the FPN reads, has its own.
  AlignedBuffer tmp_a_, tmp_b_, pingpong_[2];
  Activation c13_out_, last_out_;
  ConvScratch scratch_;
  std::vector<ConstTensorView> outs_;
  Profiler* prof_ = nullptr;
  int row_stem_ = -1, row_last_ = -1;
  DumpSink* dump_ = nullptr;
  std::string stem_name_, last_name_;
};

}  // namespace nn::detection
