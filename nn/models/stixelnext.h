// StixelNExT++: torchvision ConvNeXt features -> mean over all feature rows (the
// original AvgPool2d((40, 1)) for 1280-high inputs, extended to any height) ->
// stixel head -> prediction [n, A, 64, U] after the sigmoid.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "nn/models/convnext.h"
#include "nn/models/stixel_head.h"

namespace nn {

class StixelNExT {
 public:
  // Weights use the PyTorch state_dict names `features.*` and `classifier.*`. The head
  // variant is detected from them unless `force` names one (V1 and V3 look alike).
  // `precision` applies to the backbone's MLP GEMMs (see ConvNeXt).
  explicit StixelNExT(const weights::SafeTensors& st, std::optional<StixelHeadVariant> force = std::nullopt,
                      Precision precision = Precision::F32);

  const ConvNeXt& backbone() const { return backbone_; }
  const StixelHead& head() const { return head_; }
  std::vector<std::string> used_tensors() const;

  // Plans for NCHW inputs [n, 3, h, w] and `columns` output columns U.
  void plan(int n, int h, int w, int columns);
  int columns() const { return columns_; }
  // [n, attributes, 64, columns] values in the planned order.
  std::vector<std::int64_t> prediction_shape() const;

  // Returns the prediction (valid until the next forward). Allocates nothing.
  const float* forward(const float* input_nchw);
  Profiler& profiler() { return backbone_.profiler(); }
  // Intermediate tensors under the authors' module names: the backbone's `features.*`,
  // `avgpool`, the head's `classifier.*` and `classifier` (the prediction). Null: off.
  void set_dump(DumpSink* sink);
  // dump.path: what the backbone and the head compute apart for a dump.
  std::string dump_path() const {
    const std::string head = head_.dump_path();
    return head.empty() ? backbone_.dump_path() : backbone_.dump_path() + "; " + head;
  }

 private:
  ConvNeXt backbone_;
  StixelHead head_;
  AlignedBuffer pooled_, prediction_;
  int columns_ = 0;
  int prof_pool_ = -1, prof_head_ = -1;
  DumpSink* dump_ = nullptr;
  std::string pool_name_ = "avgpool", head_name_ = "classifier";
};

}  // namespace nn
