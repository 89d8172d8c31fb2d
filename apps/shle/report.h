// The text outputs of `shle`: OUT/frames.csv and OUT/summary.json.
#pragma once

#include <string>
#include <vector>

#include "shle/pipeline.h"

namespace shleapp {

// Header `frame,image,box_source,x0,y0,x1,y1,points,height_raw,height_filtered`;
// the box after extension and clipping, `points` the depth-window points the
// height comes from; empty fields where a frame has no box or no height, never NaN.
std::string frames_csv(const shle::SequenceRun& run);

struct DetectorDescription {
  std::string model, weights;
  int classes = 0;
  std::vector<int> labels;
  double score_threshold = 0;
};

struct RunDescription {
  std::string sequence, layout, calibration, box_source, box_rule, tracker;
  shle::PipelineOptions options;
  // Written as "detector" in the summary when box_source is "detector", so a
  // result says which weights made its boxes.
  DetectorDescription detector;
  // The folder / file of --boxes released-stage1 / coco-results (and --coco-images).
  std::string box_path, coco_images;
};

std::string summary_json(const shle::SequenceRun& run, const RunDescription& description);

}  // namespace shleapp
