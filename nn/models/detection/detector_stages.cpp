#include "nn/models/detection/detector_stages.h"

#include <algorithm>

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

void reserve_results(int max_proposals, int max_detections, Proposals* proposals, Detections* detections) {
  const std::size_t rois = static_cast<std::size_t>(std::max(max_proposals, 0));
  proposals->boxes.reserve(rois);
  proposals->scores.reserve(rois);
  const std::size_t kept = static_cast<std::size_t>(std::max(max_detections, 0));
  detections->boxes.reserve(kept);
  detections->scores.reserve(kept);
  detections->labels.reserve(kept);
}

void attach_dump(Backbone& body, Fpn& fpn, Rpn& rpn, RoiHeads& heads, DumpSink* sink) {
  body.set_dump(sink);
  fpn.set_dump(sink);
  rpn.set_dump(sink);
  heads.set_dump(sink);
}

const std::vector<ConstTensorView>& run_pyramid(Backbone& body, Fpn& fpn, const ConstTensorView& input,
                                                Profiler& prof, int row_body, int row_fpn, DumpSink* dump,
                                                const PyramidDumpNames& names) {
  const std::vector<ConstTensorView>* feats;
  const std::vector<ConstTensorView>* pyramid;
  {
    Profiler::Scope t(&prof, row_body);
    feats = &body.forward(input);
  }
  if (dump)
    for (std::size_t i = 0; i < feats->size() && i < names.body.size(); ++i)
      dump_nhwc(dump, names.body[i], (*feats)[i]);
  {
    Profiler::Scope t(&prof, row_fpn);
    pyramid = &fpn.forward(*feats);
  }
  if (dump)
    for (const auto& set : names.pyramid)
      for (std::size_t i = 0; i < pyramid->size() && i < set.size(); ++i) dump_nhwc(dump, set[i], (*pyramid)[i]);
  return *pyramid;
}

void run_rpn(Rpn& rpn, const std::vector<ConstTensorView>& pyramid, const ImageSizes& sizes, Profiler& prof,
             int row, Proposals* out) {
  Profiler::Scope t(&prof, row);
  const Proposals& p = rpn.forward(pyramid, sizes);
  out->boxes.assign(p.boxes.begin(), p.boxes.end());
  out->scores.assign(p.scores.begin(), p.scores.end());
}

}  // namespace nn::detection
