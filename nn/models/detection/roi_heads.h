// torchvision's RoIHeads at inference: MultiScaleRoIAlign (7x7, sampling ratio 2,
// aligned=False, level mapper over the pooled maps), TwoMLPHead, FastRCNNPredictor
// and postprocess_detections (softmax, class-wise decode with weights (10,10,5,5),
// clip, score > thresh, small-box removal, per-class NMS, top detections).
// detectron2's StandardROIHeads (ROIPooler with ROIAlignV2, FastRCNNConvFCHead,
// FastRCNNOutputLayers, fast_rcnn_inference) is the same maths with the choices in
// RoiHeadsConfig below.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "nn/gemm.h"
#include "nn/profiler.h"
#include "nn/models/detection/box_ops.h"
#include "nn/dump.h"
#include "nn/models/detection/layers.h"
#include "nn/models/detection/roi_align_kernel.h"
#include "nn/models/detection/transform.h"

namespace nn::detection {

struct RoiHeadsConfig {
  float score_thresh = 0.05f;
  double nms_thresh = 0.5;
  int detections_per_img = 100;
  float min_size = 1e-2f;
  int num_classes = 0;  // 0: as the weights hold; more than they hold is an error
  // Pooling: torchvision's MultiScaleRoIAlign (aligned=false, 2x2 samples) or
  // detectron2's ROIAlignV2 (aligned=true, sampling_ratio 0: adaptive).
  bool aligned = false;
  int sampling_ratio = 2;
  // Level rule floor(4 + log2(sqrt(area) / 224 + level_eps_in_log) + level_eps),
  // clamped: torchvision adds 1e-6 after the log, detectron2 1e-8 inside it.
  float level_eps_in_log = 0.0f, level_eps = 1e-6f;
  // detectron2: the background is the LAST score column, bbox_pred holds boxes of the
  // foreground classes only, and labels are 0-based foreground classes.
  bool background_last = false;
  bool drop_non_finite = false;  // drop proposals with a non-finite score or box
  WeightLayout layout = WeightLayout::Torchvision;  // detectron2: box_head.fc1/fc2
};

// detectron2's ROI heads at inference (Base-RCNN-FPN, faster_rcnn_R_50_FPN_3x).
RoiHeadsConfig detectron2_roi_heads_config();

struct Detections {
  std::vector<Box> boxes;  // resized-image pixels until rescaled
  std::vector<float> scores;
  std::vector<std::int64_t> labels;
};

class RoiHeads {
 public:
  static constexpr int kPool = 7, kChannels = 256;
  RoiHeads(const weights::SafeTensors& st, const std::string& prefix, const RoiHeadsConfig& cfg);
  // Number of classes (background included) the predictor holds.
  static int classes_in(const weights::SafeTensors& st, const std::string& prefix);
  static std::vector<weights::TensorSpec> tensor_specs(const std::string& prefix, int classes, int hidden = 1024,
                                                       WeightLayout layout = WeightLayout::Torchvision);
  int num_classes() const { return classes_; }

  // pooled: the maps the RoI pooler may sample (torchvision's '0'..'3' present). Rows
  // for RoIAlign, fc6, fc7, the predictor and the post-processing go into `layers`
  // (may be null).
  void plan(const std::vector<Shape>& pooled, const ImageSizes& sizes, int max_rois, Profiler* layers = nullptr);
  // The result stays valid until the next forward; no allocation once planned.
  const Detections& forward(const std::vector<ConstTensorView>& pooled, const std::vector<Box>& proposals,
                            const ImageSizes& sizes);
  // roi_heads.box_roi_pool [R, 256, 7, 7], roi_heads.box_head [R, 1024] (fc6, ReLU,
  // fc7, ReLU fused: covers fc6 and fc7), roi_heads.box_predictor.cls_score [R, C],
  // .bbox_pred [R, 4C] and the predictor's tuple [0] / [1] (nn/dump.h). Null: off.
  void set_dump(DumpSink* sink) { dump_ = sink; }

 private:
  DumpSink* dump_ = nullptr;
  bool predictor_whole_ = true;  // every class of the weights in use
  std::string prefix_, pool_name_, head_name_, head_covers_, cls_name_, box_name_, pred0_name_, pred1_name_;
  RoiHeadsConfig cfg_;
  int classes_ = 0, hidden_ = 1024;
  int box_classes_ = 0;  // classes with box deltas: all, or all but detectron2's background
  GemmWeights fc6_, fc7_, predictor_;
  AlignedBuffer fc6_bias_, fc7_bias_, predictor_bias_;
  std::vector<float> scales_;
  int k_min_ = 0, k_max_ = 0;
  AlignedBuffer features_, h6_, h7_, logits_;
  // One bin's RoIAlign samples per thread (adaptive sampling), planned.
  std::vector<RoiSample> samples_;
  std::size_t sample_room_ = 0;
  // Post-processing scratch, sized at plan time.
  std::vector<Box> boxes_;
  std::vector<float> scores_, prob_;
  std::vector<int> labels_, keep_;
  NmsWorkspace nms_;
  Detections result_;
  Profiler* prof_ = nullptr;
  int row_pool_ = -1, row_fc6_ = -1, row_fc7_ = -1, row_predictor_ = -1, row_post_ = -1;
};

}  // namespace nn::detection
