// The stages torchvision's and detectron2's Faster R-CNNs share after their input
// transforms: body + FPN (planned by a dry run, run timed and dumped), the RPN (its
// proposals copied out), and the results reserved at plan time.
#pragma once

#include <string>
#include <vector>

#include "nn/models/detection/backbone.h"
#include "nn/models/detection/fpn.h"
#include "nn/models/detection/roi_heads.h"
#include "nn/models/detection/rpn.h"

namespace nn::detection {

struct PyramidShapes {
  std::vector<Shape> features;  // the body's outputs, the FPN's inputs
  std::vector<Shape> pyramid;   // the FPN's outputs, the last one its max-pooled level
};

// Plans body and FPN for `input` ({1, padded_h, padded_w, 3}, planned) by a dry run of
// each part's size rules. Rows per layer go into `layers` (may be null).
PyramidShapes plan_pyramid(Backbone& body, Fpn& fpn, const ConstTensorView& input, Profiler* layers);

// Room for every proposal and detection a forward can produce.
void reserve_results(int max_proposals, int max_detections, Proposals* proposals, Detections* detections);

// Every part's dump sink (null: off).
void attach_dump(Backbone& body, Fpn& fpn, Rpn& rpn, RoiHeads& heads, DumpSink* sink);

// The names each feature map is dumped under: the body's outputs, and the pyramid's
// under one or more names each (torchvision returns it twice, from the FPN and from
// the backbone).
struct PyramidDumpNames {
  std::vector<std::string> body;
  std::vector<std::vector<std::string>> pyramid;
};

// Body then FPN, timed into rows row_body / row_fpn of `prof`, outputs dumped when
// `dump` is set. The result stays valid until the next forward.
const std::vector<ConstTensorView>& run_pyramid(Backbone& body, Fpn& fpn, const ConstTensorView& input,
                                                Profiler& prof, int row_body, int row_fpn, DumpSink* dump,
                                                const PyramidDumpNames& names);

// The RPN on the pyramid, timed into row `row`; its proposals copied into `out`.
void run_rpn(Rpn& rpn, const std::vector<ConstTensorView>& pyramid, const ImageSizes& sizes, Profiler& prof,
             int row, Proposals* out);

}  // namespace nn::detection
