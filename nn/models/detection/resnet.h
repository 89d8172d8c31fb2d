// torchvision's ResNet-50 body as resnet_fpn_backbone uses it (v1.5: stride in the
// 3x3 conv; frozen batch norm folded at load), returning layer1..layer4 outputs
// (256/512/1024/2048 channels at strides 4/8/16/32).
#pragma once

#include <string>
#include <vector>

#include "nn/models/detection/backbone.h"
#include "nn/models/detection/layers.h"

namespace nn::detection {

class ResNet50Backbone : public Backbone {
 public:
  // prefix: "backbone.body."; eps: 1e-5, or 0.0 for torchvision's COCO_V1 weights.
  ResNet50Backbone(const weights::SafeTensors& st, const std::string& prefix, float eps = 1e-5f);
  static std::vector<weights::TensorSpec> tensor_specs(const std::string& prefix);

  std::vector<int> out_channels() const override { return {256, 512, 1024, 2048}; }
  void plan(int h, int w) override;
  const std::vector<ConstTensorView>& forward(const ConstTensorView& in) override;

 private:
  struct Bottleneck {
    Conv2dWeights conv1, conv2, conv3, downsample;
    bool has_downsample = false;
    Activation a, b, identity, out;
  };
  Conv2dWeights stem_;
  Activation stem_out_, pooled_;
  std::vector<std::vector<Bottleneck>> layers_;
  ConvScratch scratch_;
  std::vector<ConstTensorView> outs_;
};

}  // namespace nn::detection
