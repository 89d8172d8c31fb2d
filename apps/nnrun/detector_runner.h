// nnrun --model fasterrcnn_*: torchvision Faster R-CNN detectors (see detector_runner.cpp).
#pragma once

#include <memory>
#include <string>

#include "apps/nnrun/runner.h"

namespace nnrun {

std::unique_ptr<Runner> make_detector(const std::string& name, const weights::SafeTensors& w,
                                      const RunOptions& options);

}  // namespace nnrun
