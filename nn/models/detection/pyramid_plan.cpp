#include "nn/models/detection/pyramid_plan.h"

namespace nn::detection {

PyramidShapes plan_pyramid(Backbone& body, Fpn& fpn, const ConstTensorView& input, Profiler* layers) {
  PyramidShapes s;
  body.plan(input.shape.h, input.shape.w, layers);
  const std::vector<ConstTensorView> feats = body.forward(input);
  for (const auto& f : feats) s.features.push_back(f.shape);
  fpn.plan(s.features);
  for (const auto& p : fpn.forward(feats)) s.pyramid.push_back(p.shape);
  return s;
}

}  // namespace nn::detection
