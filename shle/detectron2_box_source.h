// Candidates from detectron2's Faster R-CNN R50-FPN (nn/models/detection/
// detectron2_faster_rcnn.h) on every frame's left image: the `shle --boxes detector
// --detector-model detectron2_faster_rcnn_r50_fpn` source, i.e. the released stage 1's
// detector run from its own model_final.pth (converted by weights/export.py). Labels
// are detectron2's 0-based foreground classes.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "nn/models/detection/detectron2_faster_rcnn.h"
#include "shle/detector_box_source.h"

namespace shle {

class Detectron2BoxSource : public BoxSource {
 public:
  // options.labels: 0-based classes (empty: all K). Errors name the weights file, as
  // DetectorBoxSource's.
  Detectron2BoxSource(const std::string& weights_path, const DetectorOptions& options = {});
  Detectron2BoxSource(const weights::SafeTensors& weights, const DetectorOptions& options = {});

  std::string name() const override { return "detector"; }
  bool needs_image() const override { return true; }
  std::vector<Candidate> candidates(const FrameContext& frame) override;

  int num_classes() const { return model_->num_classes(); }  // K, the background excluded
  const std::vector<int>& labels() const { return labels_; }
  const nn::detection::Detections& last_detections() const { return last_; }

 private:
  std::string source_;
  DetectorOptions options_;
  std::unique_ptr<nn::detection::Detectron2FasterRcnn> model_;
  std::vector<int> labels_;
  int planned_w_ = 0, planned_h_ = 0;
  nn::detection::Detections last_;
};

}  // namespace shle
