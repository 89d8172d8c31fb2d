// What the detector needs from a backbone body: the feature maps the FPN consumes.
#pragma once

#include <vector>

#include "nn/profiler.h"
#include "nn/tensor.h"

namespace nn::detection {

class Backbone {
 public:
  virtual ~Backbone() = default;
  virtual std::vector<int> out_channels() const = 0;
  // Plans every buffer for an h x w input; registers one row per layer in `layers`
  // (may be null), which forward() then times when it is enabled.
  virtual void plan(int h, int w, Profiler* layers) = 0;
  // in: {1, h, w, 3}. Views stay valid until the next forward.
  virtual const std::vector<ConstTensorView>& forward(const ConstTensorView& in) = 0;
};

}  // namespace nn::detection
