// torchvision's FeaturePyramidNetwork with LastLevelMaxPool: 1x1 laterals, top-down
// nearest upsampling added to the lateral, 3x3 outputs, and 'pool' = the last output
// subsampled by 2 (max_pool2d with kernel 1). Outputs are ordered '0', '1', ..., 'pool'.
#pragma once

#include <string>
#include <vector>

#include "nn/dump.h"
#include "nn/models/detection/layers.h"

namespace nn::detection {

class Fpn {
 public:
  static constexpr int kChannels = 256;
  Fpn(const weights::SafeTensors& st, const std::string& prefix, const std::vector<int>& in_channels);
  static std::vector<weights::TensorSpec> tensor_specs(const std::string& prefix, const std::vector<int>& in_channels);

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
  std::vector<std::string> inner_names_, layer_names_;
  std::vector<Conv2dWeights> inner_, layer_;
  std::vector<Activation> inner_out_, upsampled_, out_;
  Activation pool_;
  ConvScratch scratch_;
  std::vector<ConstTensorView> result_;
};

}  // namespace nn::detection
