// The text outputs of `shle`: OUT/frames.csv and OUT/summary.json.
#pragma once

#include <string>

#include "shle/pipeline.h"

namespace shleapp {

// Header `frame,image,box_source,x0,y0,x1,y1,points,height_raw,height_filtered`;
// the box after extension and clipping, `points` the depth-window points the
// height comes from; empty fields where a frame has no box or no height, never NaN.
std::string frames_csv(const shle::SequenceRun& run);

struct RunDescription {
  std::string sequence, layout, calibration, box_source, box_rule, tracker;
  shle::PipelineOptions options;
};

std::string summary_json(const shle::SequenceRun& run, const RunDescription& description);

}  // namespace shleapp
