// Candidates from torchvision's Faster R-CNN (nn/models/detection) run on every
// frame's left image: the `shle --boxes detector` source. The detector is the
// category-agnostic height-limit detector of the SHLE paper, trained with
// torchvision; its weights use torchvision's state_dict names.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "nn/models/detection/faster_rcnn.h"
#include "shle/box_source.h"

namespace shle {

struct DetectorOptions {
  // Detections with score > this are candidates. It is also passed to the RoI
  // heads as torchvision's box_score_thresh (FasterRcnnConfig::roi_heads), which
  // gives the same boxes as the default 0.05 followed by a filter (NMS lets only
  // higher scores suppress lower ones, and top-100 keeps the highest) while
  // decoding fewer boxes.
  double score_threshold = 0.3;
  // Labels that count as a height-limit device; empty: every foreground label
  // 1..num_classes-1 (a category-agnostic detector has just label 1).
  std::vector<int> labels;
};

// Detections -> candidates: keeps a detection when its label is in `labels`
// (sorted or not; empty = every label >= 1), its score > score_threshold and its
// box is finite with x2 > x1 and y2 > y1. Clipping at the image border can leave
// a zero-sized box; stage 2 and the tracker must never see one.
std::vector<Candidate> detections_to_candidates(const nn::detection::Detections& det, const std::vector<int>& labels,
                                                double score_threshold);

// 8-bit interleaved RGB -> planar [3, H, W] floats in [0, 1] (what torchvision's
// model receives). Reuses `out`'s storage.
void rgb_to_chw01(const RgbImage& image, std::vector<float>* out);

// The frame's decoded left image, checked for a detector (throws shle::Error naming
// the image: no image, or a pixel buffer of the wrong size); *where names it.
const RgbImage& detector_frame_image(const FrameContext& frame, std::string* where);

// Plans `model` for a width x height frame unless it is planned for that size already
// (*planned_w / *planned_h: the planned size, 0 after a failed plan). Planning
// allocates every buffer for a size; a sequence normally has one.
template <class Model>
void plan_for_frame(Model& model, int width, int height, int* planned_w, int* planned_h) {
  if (width == *planned_w && height == *planned_h) return;
  *planned_w = *planned_h = 0;  // a failed plan must not leave a stale size behind
  model.plan(height, width);
  *planned_w = width, *planned_h = height;
}

class DetectorBoxSource : public BoxSource {
 public:
  // Errors name the weights file: a file that is not safetensors (weights::Error),
  // weights of another architecture (the first missing or unexpected tensor), a
  // label the weights do not hold, or a score threshold outside [0, 1).
  DetectorBoxSource(const std::string& weights_path, nn::detection::FasterRcnnVariant variant,
                    const DetectorOptions& options = {});
  DetectorBoxSource(const weights::SafeTensors& weights, nn::detection::FasterRcnnVariant variant,
                    const DetectorOptions& options = {});

  std::string name() const override { return "detector"; }
  bool needs_image() const override { return true; }
  // Throws shle::Error naming the image for an image the detector cannot take
  // (smaller than 32 px, or a pixel buffer of the wrong size).
  std::vector<Candidate> candidates(const FrameContext& frame) override;

  int num_classes() const { return model_->num_classes(); }
  // The labels in use, resolved (never empty).
  const std::vector<int>& labels() const { return labels_; }
  const nn::detection::FasterRcnn& model() const { return *model_; }
  // The detections of the last frame before filtering, for tests and tools.
  const nn::detection::Detections& last_detections() const { return last_; }

 private:
  std::string source_;
  DetectorOptions options_;
  std::unique_ptr<nn::detection::FasterRcnn> model_;
  std::vector<int> labels_;
  std::vector<float> chw_;  // the frame as the model's input, kept across frames
  int planned_w_ = 0, planned_h_ = 0;
  nn::detection::Detections last_;
};

}  // namespace shle
