// The detectors' output tensors as nnrun writes them (boxes, scores, labels; the RPN's
// proposals on request), shared by the torchvision and detectron2 runners.
#pragma once

#include <string>

#include "nn/models/detection/roi_heads.h"
#include "nn/models/detection/rpn.h"
#include "weights/safetensors.h"

namespace nnrun {

// `boxes` F32 [K, 4] (x1, y1, x2, y2), `scores` F32 [K], and the labels I64 [K] under
// `label_name` ("labels": torchvision's 1-based, "classes": detectron2's 0-based).
void write_detections(weights::Writer& out, const nn::detection::Detections& d, const std::string& label_name);

// `proposals` F32 [P, 4] in the resized image's pixels, their scores F32 [P] under
// `score_name`, and `proposal_image_size` I64 [2] = resized H, W.
void write_proposals(weights::Writer& out, const nn::detection::Proposals& p, const std::string& score_name,
                     const nn::detection::ImageSizes& sizes);

}  // namespace nnrun
