// torchvision's Faster R-CNN (eval) on the engine: GeneralizedRCNNTransform ->
// backbone + FPN -> RPN -> RoI heads -> boxes in original-image pixels.
// Weights use torchvision's state_dict names; the class count comes from the
// predictor's shape.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "nn/models/detection/fpn.h"
#include "nn/models/detection/backbone.h"
#include "nn/models/detection/detector_stages.h"
#include "nn/models/detection/roi_heads.h"
#include "nn/models/detection/rpn.h"
#include "nn/models/detection/transform.h"
#include "nn/profiler.h"

namespace nn::detection {

enum class FasterRcnnVariant { MobileNetV3LargeFpn, MobileNetV3Large320Fpn, ResNet50Fpn };

// "fasterrcnn_mobilenet_v3_large_fpn", "fasterrcnn_mobilenet_v3_large_320_fpn",
// "fasterrcnn_resnet50_fpn".
const char* faster_rcnn_name(FasterRcnnVariant v);
bool parse_faster_rcnn(const std::string& name, FasterRcnnVariant* out);

struct FasterRcnnConfig {
  TransformConfig transform;
  RpnConfig rpn;
  RoiHeadsConfig roi_heads;
  float bn_eps = 1e-5f;  // 0.0 for torchvision's resnet50 COCO_V1 weights
};

// torchvision 0.14's builder defaults for the variant (reference table §1).
FasterRcnnConfig faster_rcnn_defaults(FasterRcnnVariant v);

// Every tensor of the variant with `classes` classes (background included).
std::vector<weights::TensorSpec> faster_rcnn_tensor_specs(FasterRcnnVariant v, int classes);

class FasterRcnn {
 public:
  // Throws weights::Error naming the first missing, misshapen or unexpected tensor.
  FasterRcnn(const weights::SafeTensors& st, FasterRcnnVariant v);
  FasterRcnn(const weights::SafeTensors& st, FasterRcnnVariant v, const FasterRcnnConfig& cfg);

  const std::vector<weights::TensorSpec>& tensor_specs() const { return specs_; }
  int num_classes() const { return roi_heads_.num_classes(); }
  const FasterRcnnConfig& config() const { return cfg_; }

  // Plans every buffer for h x w inputs (throws below 32 px).
  void plan(int h, int w);
  // image: [3, h, w] RGB in [0, 1]. Boxes in original-image pixels. The result
  // stays valid until the next forward; nothing is allocated once planned.
  const Detections& forward(const float* image);

  // Intermediate results of the last forward, for tests and --dump-proposals.
  const ImageSizes& sizes() const { return sizes_; }
  ConstTensorView transformed() const { return input_.cview(); }
  const Proposals& proposals() const { return proposals_; }
  // Per stage (transform, backbone.body, backbone.fpn, rpn, roi_heads) and, apart,
  // per layer of the backbone body and per part of the RoI heads.
  Profiler& profiler() { return profiler_; }
  Profiler& layer_profiler() { return layer_profiler_; }

  // Intermediate tensors of the next forwards under torchvision's module names
  // (nn/dump.h): transform[0], the body's layers (ResNet-50) and outputs
  // backbone.body[i], the FPN's blocks and outputs backbone.fpn[k] / backbone[k], the
  // RPN head per level, rpn[0][0] (proposals), the RoI heads. Null: off. plan()'s
  // shape-finding dry run never dumps.
  void set_dump(DumpSink* sink);

 private:
  void attach_dump(DumpSink* sink);
  DumpSink* dump_ = nullptr;
  std::string transform_name_, proposals_name_;
  PyramidDumpNames dump_names_;
  FasterRcnnConfig cfg_;
  std::vector<weights::TensorSpec> specs_;
  BackboneHolder backbone_;
  Fpn fpn_;
  Rpn rpn_;
  RoiHeads roi_heads_;
  ImageSizes sizes_;
  Activation input_, normalised_, resized_;
  Proposals proposals_;
  std::vector<ConstTensorView> pooled_;  // the pyramid without 'pool'
  Detections detections_;
  Profiler profiler_, layer_profiler_;
  int planned_h_ = 0, planned_w_ = 0;
  int prof_transform_ = 0, prof_backbone_ = 0, prof_fpn_ = 0, prof_rpn_ = 0, prof_roi_ = 0;
};

}  // namespace nn::detection
