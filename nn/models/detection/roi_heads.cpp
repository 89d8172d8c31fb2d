#include "nn/threads.h"
#include "nn/models/detection/roi_heads.h"

#include <algorithm>
#include <cmath>

#include "nn/error.h"
#include "nn/models/detection/roi_align.h"

namespace nn::detection {

namespace {

void copy_to(AlignedBuffer& dst, const std::vector<float>& src) {
  dst.resize(src.size());
  std::copy(src.begin(), src.end(), dst.data());
}

// MultiScaleRoIAlign.infer_scale: 2 ** round(log2(feature / image)) along the height.
float infer_scale(int feature, int image) {
  const float approx = static_cast<float>(feature) / static_cast<float>(image);
  return std::pow(2.0f, std::nearbyint(std::log2(approx)));
}

// fast_rcnn_inference_single_image's valid_mask: every score and every class's
// decoded box of the proposal finite.
bool finite_prediction(const Box& proposal, const float* row, const float* prob, int first, int last,
                       const BoxCoderWeights& weights) {
  const int c = last - first + 1;
  for (int k = 0; k < c; ++k)
    if (!std::isfinite(prob[k])) return false;
  for (int k = first; k < last; ++k) {
    const Box b = decode_box(proposal, row + c + 4 * k, weights);
    if (!(std::isfinite(b.x1) && std::isfinite(b.y1) && std::isfinite(b.x2) && std::isfinite(b.y2))) return false;
  }
  return true;
}

// The box head's two layers: torchvision's TwoMLPHead fc6/fc7, detectron2's
// FastRCNNConvFCHead fc1/fc2.
std::string fc_name(const std::string& p, WeightLayout layout, int i) {
  return p + "box_head.fc" + std::to_string(layout == WeightLayout::Detectron2 ? i : i + 5) + ".";
}

}  // namespace

RoiHeadsConfig detectron2_roi_heads_config() {
  RoiHeadsConfig c;
  c.min_size = -INFINITY;  // no small-box removal
  c.aligned = true;
  c.sampling_ratio = 0;
  c.level_eps_in_log = 1e-8f;
  c.level_eps = 0.0f;
  c.background_last = true;
  c.drop_non_finite = true;
  c.layout = WeightLayout::Detectron2;
  return c;
}

int RoiHeads::classes_in(const weights::SafeTensors& st, const std::string& p) {
  const std::string name = p + "box_predictor.cls_score.weight";
  if (!st.has(name)) throw weights::Error(st.source() + ": missing tensor '" + name + "' (expected shape [C, 1024])");
  const auto& s = st.info(name).shape;
  if (s.size() != 2 || s[0] < 1 || s[0] > 100000)
    throw weights::Error(st.source() + ": tensor '" + name + "' has shape " + weights::shape_str(s) +
                         ", expected [C, 1024]");
  return static_cast<int>(s[0]);
}

std::vector<weights::TensorSpec> RoiHeads::tensor_specs(const std::string& p, int c, int hidden,
                                                       WeightLayout layout) {
  const int in = kChannels * kPool * kPool;
  const std::string fc1 = fc_name(p, layout, 1), fc2 = fc_name(p, layout, 2);
  const int boxes = layout == WeightLayout::Detectron2 ? c - 1 : c;  // detectron2 has no background box
  return {{fc1 + "weight", {hidden, in}},       {fc1 + "bias", {hidden}},
          {fc2 + "weight", {hidden, hidden}},   {fc2 + "bias", {hidden}},
          {p + "box_predictor.cls_score.weight", {c, hidden}}, {p + "box_predictor.cls_score.bias", {c}},
          {p + "box_predictor.bbox_pred.weight", {4 * boxes, hidden}}, {p + "box_predictor.bbox_pred.bias", {4 * boxes}}};
}

RoiHeads::RoiHeads(const weights::SafeTensors& st, const std::string& p, const RoiHeadsConfig& cfg) : cfg_(cfg) {
  classes_ = classes_in(st, p);
  if (cfg.num_classes > classes_)
    throw Error(st.source() + ": " + std::to_string(cfg.num_classes) + " classes requested but the weights hold " +
                std::to_string(classes_) + " ('" + p + "box_predictor.cls_score.weight' is [" +
                std::to_string(classes_) + ", 1024])");
  predictor_whole_ = cfg.num_classes <= 0 || cfg.num_classes == classes_;
  if (cfg.background_last && !predictor_whole_)
    throw Error(st.source() + ": a class subset needs the background first (torchvision's layout)");
  if (cfg.background_last && classes_ < 2)
    throw Error(st.source() + ": '" + p + "box_predictor.cls_score.weight' has " + std::to_string(classes_) +
                " row(s), expected K + 1 >= 2 (the classes and the background)");
  if (cfg.num_classes > 0) classes_ = cfg.num_classes;
  box_classes_ = cfg.background_last ? classes_ - 1 : classes_;
  const bool d2 = cfg.layout == WeightLayout::Detectron2;
  const std::string fc1 = fc_name(p, cfg.layout, 1), fc2 = fc_name(p, cfg.layout, 2);
  prefix_ = p;
  pool_name_ = p + (d2 ? "box_pooler" : "box_roi_pool");
  head_name_ = p + "box_head";
  head_covers_ = fc1.substr(0, fc1.size() - 1) + "," + fc2.substr(0, fc2.size() - 1);
  cls_name_ = p + "box_predictor.cls_score";
  box_name_ = p + "box_predictor.bbox_pred";
  pred0_name_ = p + "box_predictor[0]";
  pred1_name_ = p + "box_predictor[1]";
  const int in = kChannels * kPool * kPool;
  // fc6 reads torchvision's (C, 7, 7) flattening; our RoI features are (7, 7, C).
  const auto w6 = st.f32(fc1 + "weight");
  std::vector<float> w6p(w6.size());
  for (int o = 0; o < hidden_; ++o)
    for (int c = 0; c < kChannels; ++c)
      for (int yx = 0; yx < kPool * kPool; ++yx)
        w6p[static_cast<std::size_t>(o) * in + yx * kChannels + c] = w6[static_cast<std::size_t>(o) * in + c * kPool * kPool + yx];
  fc6_ = GemmWeights::pack(w6p.data(), hidden_, in);
  copy_to(fc6_bias_, st.f32(fc1 + "bias"));
  fc7_ = GemmWeights::pack(st.f32(fc2 + "weight").data(), hidden_, hidden_);
  copy_to(fc7_bias_, st.f32(fc2 + "bias"));
  // Class score and box rows of the classes in use, in one product: C scores, then
  // 4 deltas per class with a box (box_classes_).
  const auto cw = st.f32(p + "box_predictor.cls_score.weight"), cb = st.f32(p + "box_predictor.cls_score.bias");
  const auto bw = st.f32(p + "box_predictor.bbox_pred.weight"), bb = st.f32(p + "box_predictor.bbox_pred.bias");
  std::vector<float> w(cw.begin(), cw.begin() + static_cast<std::ptrdiff_t>(classes_) * hidden_);
  w.insert(w.end(), bw.begin(), bw.begin() + static_cast<std::ptrdiff_t>(4 * box_classes_) * hidden_);
  std::vector<float> b(cb.begin(), cb.begin() + classes_);
  b.insert(b.end(), bb.begin(), bb.begin() + 4 * box_classes_);
  predictor_ = GemmWeights::pack(w.data(), classes_ + 4 * box_classes_, hidden_);
  copy_to(predictor_bias_, b);
}

void RoiHeads::plan(const std::vector<Shape>& pooled, const ImageSizes& sizes, int max_rois, Profiler* prof) {
  prof_ = prof;
  if (prof) {
    // Work at max_rois RoIs (what the RPN returns at most).
    const int rois = std::max(1, max_rois);
    const double r = rois, in = kChannels * kPool * kPool;
    const std::string shape = "[" + std::to_string(rois) + ", " + std::to_string(hidden_) + "]";
    const std::string fc1 = fc_name(prefix_, cfg_.layout, 1), fc2 = fc_name(prefix_, cfg_.layout, 2);
    row_pool_ = prof->add(pool_name_, cfg_.sampling_ratio > 0 ? "RoIAlign 7x7, 2x2 samples"
                                                               : "RoIAlignV2 7x7, adaptive samples", "", 0);
    row_fc6_ = prof->add(fc1.substr(0, fc1.size() - 1), "linear + relu", shape, 2.0 * r * in * hidden_);
    row_fc7_ = prof->add(fc2.substr(0, fc2.size() - 1), "linear + relu", shape, 2.0 * r * hidden_ * hidden_);
    row_predictor_ = prof->add(prefix_ + "box_predictor", "linear (scores, deltas)", "",
                               2.0 * r * hidden_ * (classes_ + 4 * box_classes_));
    row_post_ = prof->add(prefix_ + "postprocess", "softmax, decode, NMS, top-k", "", 0);
  }
  scales_.clear();
  for (const Shape& s : pooled) scales_.push_back(infer_scale(s.h, sizes.resized_h));
  k_min_ = static_cast<int>(-std::log2(scales_.front()));
  k_max_ = static_cast<int>(-std::log2(scales_.back()));
  // RoIs lie inside the resized image (the RPN clips them): bins take at most this
  // many samples on the finest level.
  RoiAlignParams rp;
  rp.out_h = rp.out_w = kPool;
  rp.sampling_ratio = cfg_.sampling_ratio;
  sample_room_ = 0;
  for (float s : scales_)
    sample_room_ = std::max(sample_room_, roi_align_max_samples(rp, sizes.resized_h * s, sizes.resized_w * s));
  samples_.resize(sample_room_ * static_cast<std::size_t>(std::max(1, num_threads())));
  const std::size_t rois = std::max(1, max_rois);
  features_.resize(rois * kChannels * kPool * kPool);
  h6_.resize(rois * hidden_);
  h7_.resize(rois * hidden_);
  logits_.resize(rois * (classes_ + 4 * box_classes_));
  const std::size_t candidates = rois * static_cast<std::size_t>(classes_);
  boxes_.reserve(candidates);
  scores_.reserve(candidates);
  labels_.reserve(candidates);
  keep_.reserve(candidates);
  nms_.reserve(candidates);
  prob_.resize(classes_);
  const std::size_t kept = static_cast<std::size_t>(std::max(cfg_.detections_per_img, 0));
  result_.boxes.reserve(kept);
  result_.scores.reserve(kept);
  result_.labels.reserve(kept);
}

const Detections& RoiHeads::forward(const std::vector<ConstTensorView>& pooled, const std::vector<Box>& proposals,
                                    const ImageSizes& sizes) {
  const int r = static_cast<int>(proposals.size());
  Detections& det = result_;
  det.boxes.clear(), det.scores.clear(), det.labels.clear();
  if (r == 0) return det;
  if (static_cast<std::size_t>(r) * hidden_ > h6_.size()) throw Error("RoI heads: more proposals than planned");
  const std::size_t per_roi = static_cast<std::size_t>(kChannels) * kPool * kPool;
  RoiAlignParams rp;
  rp.out_h = rp.out_w = kPool;
  rp.sampling_ratio = cfg_.sampling_ratio;
  rp.aligned = cfg_.aligned;
  rp.isa = fc6_.isa();
  // A thread count raised after plan() needs more sample room (the only allocation).
  if (samples_.size() < sample_room_ * static_cast<std::size_t>(num_threads()))
    samples_.resize(sample_room_ * static_cast<std::size_t>(num_threads()));
  Profiler::Scope t_pool(prof_, row_pool_);
  parallel_for(r, true, [&](long long i_) {
    const int i = static_cast<int>(i_);
    // The level rule in float32: torchvision's LevelMapper floor(4 + log2(sqrt(area) /
    // 224) + 1e-6), detectron2's assign_boxes_to_levels floor(4 + log2(sqrt(area) / 224
    // + 1e-8)); clamped.
    const Box& b = proposals[i];
    const float s = std::sqrt((b.x2 - b.x1) * (b.y2 - b.y1));
    float lvl = std::floor(4.0f + std::log2(s / 224.0f + cfg_.level_eps_in_log) + cfg_.level_eps);
    // Written so that a NaN level (degenerate box) also lands on k_min, never out of range.
    lvl = lvl > static_cast<float>(k_min_) ? std::min(lvl, static_cast<float>(k_max_)) : static_cast<float>(k_min_);
    const int level = static_cast<int>(lvl) - k_min_;
    RoiAlignParams p = rp;
    p.spatial_scale = scales_[level];
    roi_align_one(pooled[level], 0, b, p, features_.data() + i * per_roi,
                  samples_.data() + sample_room_ * static_cast<std::size_t>(thread_index()), sample_room_);
  });
  t_pool.stop();
  // y = act(x W^T + b) over the r RoIs, timed into profiler row `row`.
  auto linear = [&](int row, const float* x, int lda, const GemmWeights& w, const AlignedBuffer& b, Act act, float* y) {
    Profiler::Scope t(prof_, row);
    GemmEpilogue ep;
    ep.bias = b.data(), ep.act = act;
    gemm_parallel(r, x, lda, w, y, w.n(), ep);
  };
  const int c = classes_, width = classes_ + 4 * box_classes_;
  linear(row_fc6_, features_.data(), static_cast<int>(per_roi), fc6_, fc6_bias_, Act::Relu, h6_.data());
  linear(row_fc7_, h6_.data(), hidden_, fc7_, fc7_bias_, Act::Relu, h7_.data());
  linear(row_predictor_, h7_.data(), hidden_, predictor_, predictor_bias_, Act::None, logits_.data());
  if (dump_) {
    dump_nhwc(dump_, pool_name_, ConstTensorView(features_.data(), Shape{r, kPool, kPool, kChannels}));
    dump_rows(dump_, head_name_, h7_.data(), r, hidden_, 0, hidden_, head_covers_);
    if (predictor_whole_) {  // with fewer classes in use, PyTorch's rows are longer
      dump_rows(dump_, cls_name_, logits_.data(), r, width, 0, c);
      dump_rows(dump_, box_name_, logits_.data(), r, width, c, 4 * box_classes_);
      dump_rows(dump_, pred0_name_, logits_.data(), r, width, 0, c);
      dump_rows(dump_, pred1_name_, logits_.data(), r, width, c, 4 * box_classes_);
    }
  }
  Profiler::Scope t_post(prof_, row_post_);

  boxes_.clear(), scores_.clear(), labels_.clear();
  const BoxCoderWeights weights{10.0f, 10.0f, 5.0f, 5.0f};
  float* prob = prob_.data();
  // Foreground score columns, box k of bbox_pred for column k: torchvision 1..C-1
  // (0 is the background), detectron2 0..C-2 (C-1 is the background).
  const int first = cfg_.background_last ? 0 : 1, last = cfg_.background_last ? c - 1 : c;
  for (int i = 0; i < r; ++i) {
    const float* row = logits_.data() + static_cast<std::size_t>(i) * width;
    float mx = row[0];
    for (int k = 1; k < c; ++k) mx = std::max(mx, row[k]);
    float sum = 0;
    for (int k = 0; k < c; ++k) sum += (prob[k] = std::exp(row[k] - mx));
    for (int k = 0; k < c; ++k) prob[k] /= sum;
    if (cfg_.drop_non_finite && !finite_prediction(proposals[i], row, prob, first, last, weights)) continue;
    for (int k = first; k < last; ++k) {
      if (!(prob[k] > cfg_.score_thresh)) continue;
      const Box b = clip_box(decode_box(proposals[i], row + c + 4 * k, weights), sizes.resized_h, sizes.resized_w);
      if (!box_big_enough(b, cfg_.min_size)) continue;
      boxes_.push_back(b);
      scores_.push_back(prob[k]);
      labels_.push_back(k);
    }
  }
  batched_nms(boxes_, scores_, labels_, cfg_.nms_thresh, nms_, keep_);
  const std::size_t n = std::min<std::size_t>(keep_.size(), static_cast<std::size_t>(std::max(cfg_.detections_per_img, 0)));
  for (std::size_t i = 0; i < n; ++i) {
    det.boxes.push_back(boxes_[keep_[i]]);
    det.scores.push_back(scores_[keep_[i]]);
    det.labels.push_back(labels_[keep_[i]]);
  }
  return det;
}

}  // namespace nn::detection
