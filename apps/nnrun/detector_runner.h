// nnrun --model fasterrcnn_*: torchvision Faster R-CNN detectors (see detector_runner.cpp).
// nnrun --model detectron2_faster_rcnn_r50_fpn: detectron2's (detectron2_runner.cpp).
#pragma once

#include <memory>
#include <string>

#include "apps/nnrun/runner.h"

namespace nnrun {

std::unique_ptr<Runner> make_detector(const std::string& name, const weights::SafeTensors& w,
                                      const RunOptions& options);
// nnrun --model detectron2_faster_rcnn_r50_fpn (detectron2_runner.cpp).
std::unique_ptr<Runner> make_detectron2(const std::string& name, const weights::SafeTensors& w,
                                        const RunOptions& options);

}  // namespace nnrun
