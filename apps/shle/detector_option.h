// The detector options of `shle` and `shle_eval` (--detector-model, --detector-weights,
// --detector-score, --detector-labels, --threads), parsed and checked in one place, and
// the box source they describe. `shle_eval` loads the detector once for every scene.
#pragma once

#include <memory>
#include <string>

#include "apps/common/cli.h"
#include "apps/shle/report.h"
#include "nn/models/detection/detectron2_faster_rcnn.h"
#include "nn/models/detection/faster_rcnn.h"
#include "shle/box_source.h"
#include "shle/detector_box_source.h"

namespace shleapp {

struct DetectorChoice {
  // As given on the command line.
  std::string weights, model = "fasterrcnn_mobilenet_v3_large_fpn", labels;
  double score = 0.3;
  int threads = 0;
  // Filled by check_detector_options.
  bool detectron2 = false;
  nn::detection::FasterRcnnVariant variant{};
  shle::DetectorOptions options;
};

// Registers the options on `p`; `prefix` starts each help text (e.g. "dataset: ").
void add_detector_options(cli::Parser& p, DetectorChoice* d, const std::string& prefix = "");

// After p.parse(): with `used` (--boxes detector) checks the values, else refuses any
// detector option that was given; --threads applies in both cases. Fails through p.
void check_detector_options(cli::Parser& p, bool used, DetectorChoice* d);

// Loads the detector (errors name the weights file) and describes it; prints one line
// on stderr with `program`'s name unless `quiet`.
std::unique_ptr<shle::BoxSource> make_detector_source(const DetectorChoice& d, const char* program, bool quiet,
                                                      DetectorDescription* description);

}  // namespace shleapp
