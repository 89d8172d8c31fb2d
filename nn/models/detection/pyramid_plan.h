// Planning a backbone body and its FPN for one padded input size: their buffers
// follow from a dry run of each part's size rules on the (unfilled) input.
#pragma once

#include <vector>

#include "nn/models/detection/backbone.h"
#include "nn/models/detection/fpn.h"

namespace nn::detection {

struct PyramidShapes {
  std::vector<Shape> features;  // the body's outputs, the FPN's inputs
  std::vector<Shape> pyramid;   // the FPN's outputs, the last one its max-pooled level
};

// input: {1, padded_h, padded_w, 3}, planned. Rows per layer go into `layers` (may be null).
PyramidShapes plan_pyramid(Backbone& body, Fpn& fpn, const ConstTensorView& input, Profiler* layers);

}  // namespace nn::detection
