// detectron2's Faster R-CNN R50-FPN (COCO-Detection/faster_rcnn_R_50_FPN_3x, the
// detector of SHLE's stage 1) on the engine, exact to detectron2 at inference
// (docs/ENGINEERING.md, "detectron2's Faster R-CNN"): an RGB8 image of any size ->
// Pillow resize, BGR, normalise, pad -> ResNet-50 (STRIDE_IN_1X1, FrozenBN eps 1e-5)
// + FPN -> RPN -> ROIAlignV2 box head -> boxes clipped to the original image.
// Weights: the checkpoint's "model" entry under its own names (weights/export.py);
// K foreground classes, read from cls_score (K + 1 rows, the background last);
// pixel_mean / pixel_std [3, 1, 1] where an older checkpoint saved them (they replace
// the configured ones), else MODEL.PIXEL_MEAN / PIXEL_STD's defaults.
// The parts are the torchvision detector's, configured (WeightLayout::Detectron2,
// detectron2_rpn_config(), detectron2_roi_heads_config()).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "nn/models/detection/backbone.h"
#include "nn/models/detection/detector_stages.h"
#include "nn/models/detection/detectron2_transform.h"
#include "nn/models/detection/fpn.h"
#include "nn/models/detection/roi_heads.h"
#include "nn/models/detection/rpn.h"
#include "nn/profiler.h"

namespace nn::detection {

constexpr const char* kDetectron2FasterRcnnName = "detectron2_faster_rcnn_r50_fpn";

struct Detectron2FasterRcnnConfig {
  Detectron2TransformConfig transform;
  RpnConfig rpn = detectron2_rpn_config();
  RoiHeadsConfig roi_heads = detectron2_roi_heads_config();
  float bn_eps = 1e-5f;  // FrozenBatchNorm2d's
};

// The checkpoint's tensors for `classes` score rows (K foreground + background).
std::vector<weights::TensorSpec> detectron2_faster_rcnn_tensor_specs(int classes);

class Detectron2FasterRcnn {
 public:
  // Throws weights::Error naming the first missing, misshapen or unexpected tensor.
  explicit Detectron2FasterRcnn(const weights::SafeTensors& st,
                                const Detectron2FasterRcnnConfig& cfg = Detectron2FasterRcnnConfig());

  const std::vector<weights::TensorSpec>& tensor_specs() const { return specs_; }
  // Foreground classes K (detections' labels are 0..K-1).
  int num_classes() const { return roi_heads_.num_classes() - 1; }
  const Detectron2FasterRcnnConfig& config() const { return cfg_; }

  // Plans every buffer for h x w RGB8 inputs (throws below 32 px).
  void plan(int h, int w);
  // rgb: h x w x 3 RGB8, row-major. Boxes in the original image's pixels, scores,
  // 0-based labels, as detectron2's Instances. Valid until the next forward; nothing
  // is allocated once planned.
  const Detections& forward(const std::uint8_t* rgb);

  // Intermediate results of the last forward, for tests and --dump-proposals.
  const ImageSizes& sizes() const { return sizes_; }
  const std::vector<std::uint8_t>& resized() const { return transform_.resized(); }
  ConstTensorView transformed() const { return input_.cview(); }
  // The RPN's proposals in resized-image pixels with their objectness logits.
  const Proposals& proposals() const { return proposals_; }
  Profiler& profiler() { return profiler_; }
  Profiler& layer_profiler() { return layer_profiler_; }
  // Intermediate tensors under detectron2's module names (nn/dump.h); null: off.
  void set_dump(DumpSink* sink);

 private:
  void attach_dump(DumpSink* sink);
  DumpSink* dump_ = nullptr;
  PyramidDumpNames dump_names_;
  Detectron2FasterRcnnConfig cfg_;
  std::vector<weights::TensorSpec> specs_;
  BackboneHolder backbone_;
  Fpn fpn_;
  Rpn rpn_;
  RoiHeads roi_heads_;
  Detectron2Transform transform_;
  ImageSizes sizes_;
  Activation input_;
  Proposals proposals_;
  std::vector<ConstTensorView> pooled_;
  Detections detections_;
  Profiler profiler_, layer_profiler_;
  int planned_h_ = 0, planned_w_ = 0;
  int prof_transform_ = 0, prof_backbone_ = 0, prof_fpn_ = 0, prof_rpn_ = 0, prof_roi_ = 0, prof_post_ = 0;
};

}  // namespace nn::detection
