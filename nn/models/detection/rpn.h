// torchvision's RegionProposalNetwork at inference: the shared head (3x3 conv + ReLU,
// 1x1 objectness and 1x1 box deltas) on every FPN level, anchors, per-level top-k on
// the logits, decode, sigmoid, clip, small-box removal, score threshold, NMS per
// level and the global top-n. detectron2's RPN (StandardRPNHead,
// find_top_rpn_proposals) is the same maths with the choices in RpnConfig below.
#pragma once

#include <string>
#include <vector>

#include "nn/gemm.h"
#include "nn/models/detection/box_ops.h"
#include "nn/dump.h"
#include "nn/models/detection/layers.h"
#include "nn/models/detection/transform.h"

namespace nn::detection {

struct RpnConfig {
  std::vector<std::vector<float>> anchor_sizes;  // per level
  std::vector<float> aspect_ratios = {0.5f, 1.0f, 2.0f};
  int pre_nms_top_n = 1000;   // per level
  int post_nms_top_n = 1000;  // per image
  double nms_thresh = 0.7;
  float score_thresh = 0.0f;
  float min_size = 1e-3f;
  // detectron2's choices (WeightLayout::Detectron2 also renames the head's tensors):
  bool round_anchors = true;        // false: DefaultAnchorGenerator's unrounded cells
  std::vector<int> strides;         // per level; empty: padded size / grid size
  bool sigmoid_scores = true;       // false: NMS ranks by, and proposals return, logits
  bool drop_non_finite = false;     // drop candidates with a non-finite box or logit
  bool min_size_exclusive = false;  // keep sides > min_size (Boxes.nonempty), not >=
  WeightLayout layout = WeightLayout::Torchvision;
};

// detectron2's RPN at inference (Base-RCNN-FPN): unrounded anchors at the feature
// strides, top 1000 logits per level, finite filter, clip, w > 0 and h > 0, NMS 0.7
// on the logits, top 1000.
RpnConfig detectron2_rpn_config();

struct Proposals {
  std::vector<Box> boxes;    // resized-image pixels, descending score
  std::vector<float> scores;
};

class Rpn {
 public:
  Rpn(const weights::SafeTensors& st, const std::string& prefix, const RpnConfig& cfg);
  static std::vector<weights::TensorSpec> tensor_specs(const std::string& prefix, int anchors_per_cell,
                                                       WeightLayout layout = WeightLayout::Torchvision);
  int anchors_per_cell() const { return a_; }

  void plan(const std::vector<Shape>& levels, const ImageSizes& sizes);
  // The result stays valid until the next forward; no allocation once planned.
  const Proposals& forward(const std::vector<ConstTensorView>& levels, const ImageSizes& sizes);
  // Per level k: rpn.head.conv#k (conv + ReLU fused), rpn.head.cls_logits#k,
  // rpn.head.bbox_pred#k (one fused product), and RPNHead's output lists
  // rpn.head[0][k] / rpn.head[1][k] (nn/dump.h). Null: off.
  void set_dump(DumpSink* sink) { dump_ = sink; }

 private:
  DumpSink* dump_ = nullptr;
  struct LevelNames {
    std::string conv, conv_covers, cls, box, head_cls, head_box;
  };
  std::vector<LevelNames> names_;
  RpnConfig cfg_;
  std::string prefix_;  // "rpn.head." (detectron2: "proposal_generator.rpn_head.")
  int a_ = 0;
  Conv2dWeights conv_;
  GemmWeights heads_;  // objectness (A) then deltas (4A) in one product
  AlignedBuffer heads_bias_;
  std::vector<Activation> hidden_, head_out_;
  std::vector<std::vector<Box>> anchors_;
  ConvScratch scratch_;
  // Post-processing scratch, sized at plan time.
  std::vector<float> level_logits_, logits_, kept_scores_;
  std::vector<int> order_, level_of_, kept_levels_, keep_;
  std::vector<Box> boxes_, kept_boxes_;
  NmsWorkspace nms_;
  Proposals result_;
};

}  // namespace nn::detection
