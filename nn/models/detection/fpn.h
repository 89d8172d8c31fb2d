// torchvision's FeaturePyramidNetwork with LastLevelMaxPool: 1x1 laterals, top-down
// nearest upsampling added to the lateral, 3x3 outputs, and 'pool' = the last output
// subsampled by 2 (max_pool2d with kernel 1). Outputs are ordered '0', '1', ..., 'pool'.
// detectron2's FPN (LastLevelMaxPool top block, no norm, "sum" fusion) is the same
// maths under other names: fpn_lateral{2..5} / fpn_output{2..5}, outputs p2..p6.
#pragma once

#include <string>
#include <vector>

#include "nn/dump.h"
#include "nn/models/detection/layers.h"

namespace nn::detection {

class Fpn {
 public:
  static constexpr int kChannels = 256;
  // prefix: "backbone.fpn." (detectron2: "backbone.").
  Fpn(const weights::SafeTensors& st, const std::string& prefix, const std::vector<int>& in_channels,
      WeightLayout layout = WeightLayout::Torchvision);
  static std::vector<weights::TensorSpec> tensor_specs(const std::string& prefix, const std::vector<int>& in_channels,
                                                       WeightLayout layout = WeightLayout::Torchvision);

  void plan(const std::vector<Shape>& inputs);
  // Views stay valid until the next forward.
  const std::vector<ConstTensorView>& forward(const std::vector<ConstTensorView>& inputs);
  // Dumps (nn/dump.h): layer_blocks.i (= the output level i), the top lateral
  // inner_blocks.{n-1} (the others have the top-down sum fused in, no PyTorch module
  // returns them). The detector dumps the output dict. Null: off.
  void set_dump(DumpSink* sink) { dump_ = sink; }

 private:
  void dump_level(std::size_t i, bool lateral_is_module) const;
  DumpSink* dump_ = nullptr;
  // Per level: the dumped module names and the modules they cover.
  std::vector<std::string> inner_names_, inner_covers_, layer_names_, layer_covers_;
  std::vector<Conv2dWeights> inner_, layer_;
  std::vector<Activation> inner_out_, upsampled_, out_;
  Activation pool_;
  ConvScratch scratch_;
  std::vector<ConstTensorView> result_;
};

}  // namespace nn::detection
