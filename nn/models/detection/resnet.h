// The ResNet-50 body of the detectors (frozen batch norm folded at load), returning
// the four stage outputs (256/512/1024/2048 channels at strides 4/8/16/32), in one
// of two layouts that share all the maths:
//  - torchvision's as resnet_fpn_backbone uses it (v1.5: a stage's stride in the
//    first block's 3x3 conv; names conv1/bn1, layerN.i.convK/bnK, downsample.0/.1);
//  - detectron2's (STRIDE_IN_1X1: the stride in the first block's first 1x1 conv,
//    the 3x3 at stride 1; names stem.conv1(.norm), resN.i.convK(.norm),
//    shortcut(.norm)).
#pragma once

#include <string>
#include <memory>
#include <vector>

#include "nn/models/detection/backbone.h"
#include "nn/models/detection/layers.h"

namespace nn::detection {

class ResNet50Backbone : public Backbone {
 public:
  // prefix: "backbone.body." (detectron2: "backbone.bottom_up."); eps: 1e-5, or 0.0
  // for torchvision's COCO_V1 weights.
  ResNet50Backbone(const weights::SafeTensors& st, const std::string& prefix, float eps = 1e-5f,
                   WeightLayout layout = WeightLayout::Torchvision);
  static std::vector<weights::TensorSpec> tensor_specs(const std::string& prefix,
                                                       WeightLayout layout = WeightLayout::Torchvision);

  std::vector<int> out_channels() const override { return {256, 512, 1024, 2048}; }
  std::unique_ptr<Backbone> clone() const override { return std::make_unique<ResNet50Backbone>(*this); }
  void plan(int h, int w, Profiler* layers) override;
  const std::vector<ConstTensorView>& forward(const ConstTensorView& in) override;
  // backbone.body.relu (conv1+bn1+relu), .maxpool, per block .layerN.i.relu,
  // .relu#1, .downsample, .relu#2 and .layerN.i, per layer .layerN. detectron2's
  // layout: backbone.bottom_up.stem (after its max pool), resN.i.shortcut, resN.i,
  // resN (its convs' module outputs precede the functional ReLU: not dumped).
  void set_dump(DumpSink* sink) override { dump_ = sink; }

 private:
  struct Bottleneck {
    Conv2dWeights conv1, conv2, conv3, downsample;
    bool has_downsample = false;
    Shape a, b, out;  // planned output shapes of conv1, conv2, conv3 (= downsample's)
    int prow1 = -1, prow2 = -1, prow3 = -1, prow_down = -1;  // profiler rows
    // PyTorch names of the tensors the fused convs produce (conv + frozen BN + ReLU):
    // relu (after conv1/bn1), relu#1 (after conv2/bn2), downsample, the block (relu#2).
    std::string name, relu1, relu2, relu3, down, covers1, covers2, covers3, covers_down;
    std::string row1, row2;  // profiler row names of conv1, conv2 (the dump names where there are)
  };
  Conv2dWeights stem_;
  Shape stem_shape_;
  Activation pooled_;
  // Memory shared by all blocks: conv1 and conv2 outputs and the downsampled identity
  // live only inside a block; block outputs alternate between two buffers (the first
  // also holds the stem output, dead after the max pool); only each layer's last
  // output, which the FPN reads, has a buffer of its own.
  AlignedBuffer tmp_a_, tmp_b_, tmp_identity_, pingpong_[2];
  std::vector<Activation> layer_out_;
  std::vector<std::vector<Bottleneck>> layers_;
  ConvScratch scratch_;
  std::vector<ConstTensorView> outs_;
  Profiler* prof_ = nullptr;
  int row_stem_ = -1, row_pool_ = -1;
  DumpSink* dump_ = nullptr;
  std::string stem_name_, stem_row_, stem_covers_, pool_name_;
  std::vector<std::string> layer_names_;
};

}  // namespace nn::detection
