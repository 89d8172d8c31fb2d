// The frame gate of the released stage 2 (Stage2/post_process.py,
// compute_pred_success): a frame is used only when its box "hits" the ground-truth
// annotation box. It uses the ground truth, so it is an oracle: off by default
// (PipelineOptions::gate_with_annotations), offered to reproduce the released
// figures.
#pragma once

#include "shle/types.h"

namespace shle {

// The released IoU: every coordinate truncated towards zero (Python int()), areas
// with the inclusive +1 pixel convention, intersection max(0, xB - xA + 1) *
// max(0, yB - yA + 1). A zero denominator (degenerate boxes; a ZeroDivisionError in
// the released code) gives 0.
double released_iou(const Box& a, const Box& b);

// flag = IoU > 0 or (row_dis < 200 and col_dis < 20) with row_dis = |A.x1 - B.x0|
// (the predicted RIGHT edge against the annotation's LEFT edge, as released) and
// col_dis = |A.y0 - B.y0|, on the untruncated coordinates. `predicted` is the box
// before the pixel extension, `annotation` the frame's ground-truth box.
bool released_gate(const Box& predicted, const Box& annotation);

}  // namespace shle
