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

}  // namespace

int RoiHeads::classes_in(const weights::SafeTensors& st, const std::string& p) {
  const std::string name = p + "box_predictor.cls_score.weight";
  if (!st.has(name)) throw weights::Error(st.source() + ": missing tensor '" + name + "' (expected shape [C, 1024])");
  const auto& s = st.info(name).shape;
  if (s.size() != 2 || s[0] < 1 || s[0] > 100000)
    throw weights::Error(st.source() + ": tensor '" + name + "' has shape " + weights::shape_str(s) +
                         ", expected [C, 1024]");
  return static_cast<int>(s[0]);
}

std::vector<weights::TensorSpec> RoiHeads::tensor_specs(const std::string& p, int c, int hidden) {
  const int in = kChannels * kPool * kPool;
  return {{p + "box_head.fc6.weight", {hidden, in}},       {p + "box_head.fc6.bias", {hidden}},
          {p + "box_head.fc7.weight", {hidden, hidden}},   {p + "box_head.fc7.bias", {hidden}},
          {p + "box_predictor.cls_score.weight", {c, hidden}}, {p + "box_predictor.cls_score.bias", {c}},
          {p + "box_predictor.bbox_pred.weight", {4 * c, hidden}}, {p + "box_predictor.bbox_pred.bias", {4 * c}}};
}

RoiHeads::RoiHeads(const weights::SafeTensors& st, const std::string& p, const RoiHeadsConfig& cfg) : cfg_(cfg) {
  classes_ = classes_in(st, p);
  if (cfg.num_classes > classes_)
    throw Error(st.source() + ": " + std::to_string(cfg.num_classes) + " classes requested but the weights hold " +
                std::to_string(classes_) + " ('" + p + "box_predictor.cls_score.weight' is [" +
                std::to_string(classes_) + ", 1024])");
  predictor_whole_ = cfg.num_classes <= 0 || cfg.num_classes == classes_;
  if (cfg.num_classes > 0) classes_ = cfg.num_classes;
  prefix_ = p;
  pool_name_ = p + "box_roi_pool";
  head_name_ = p + "box_head";
  head_covers_ = module_list(p + "box_head.", {"fc6", "fc7"});
  cls_name_ = p + "box_predictor.cls_score";
  box_name_ = p + "box_predictor.bbox_pred";
  pred0_name_ = p + "box_predictor[0]";
  pred1_name_ = p + "box_predictor[1]";
  const int in = kChannels * kPool * kPool;
  // fc6 reads torchvision's (C, 7, 7) flattening; our RoI features are (7, 7, C).
  const auto w6 = st.f32(p + "box_head.fc6.weight");
  std::vector<float> w6p(w6.size());
  for (int o = 0; o < hidden_; ++o)
    for (int c = 0; c < kChannels; ++c)
      for (int yx = 0; yx < kPool * kPool; ++yx)
        w6p[static_cast<std::size_t>(o) * in + yx * kChannels + c] = w6[static_cast<std::size_t>(o) * in + c * kPool * kPool + yx];
  fc6_ = GemmWeights::pack(w6p.data(), hidden_, in);
  copy_to(fc6_bias_, st.f32(p + "box_head.fc6.bias"));
  fc7_ = GemmWeights::pack(st.f32(p + "box_head.fc7.weight").data(), hidden_, hidden_);
  copy_to(fc7_bias_, st.f32(p + "box_head.fc7.bias"));
  // Class score and box rows of the classes in use, in one product: C scores, then 4C deltas.
  const auto cw = st.f32(p + "box_predictor.cls_score.weight"), cb = st.f32(p + "box_predictor.cls_score.bias");
  const auto bw = st.f32(p + "box_predictor.bbox_pred.weight"), bb = st.f32(p + "box_predictor.bbox_pred.bias");
  std::vector<float> w(cw.begin(), cw.begin() + static_cast<std::ptrdiff_t>(classes_) * hidden_);
  w.insert(w.end(), bw.begin(), bw.begin() + static_cast<std::ptrdiff_t>(4 * classes_) * hidden_);
  std::vector<float> b(cb.begin(), cb.begin() + classes_);
  b.insert(b.end(), bb.begin(), bb.begin() + 4 * classes_);
  predictor_ = GemmWeights::pack(w.data(), 5 * classes_, hidden_);
  copy_to(predictor_bias_, b);
}

void RoiHeads::plan(const std::vector<Shape>& pooled, const ImageSizes& sizes, int max_rois, Profiler* prof) {
  prof_ = prof;
  if (prof) {
    // Work at max_rois RoIs (what the RPN returns at most).
    const int rois = std::max(1, max_rois);
    const double r = rois, in = kChannels * kPool * kPool;
    const std::string shape = "[" + std::to_string(rois) + ", " + std::to_string(hidden_) + "]";
    row_pool_ = prof->add("roi_heads.box_roi_pool", "RoIAlign 7x7, 2x2 samples", "", 0);
    row_fc6_ = prof->add("roi_heads.box_head.fc6", "linear + relu", shape, 2.0 * r * in * hidden_);
    row_fc7_ = prof->add("roi_heads.box_head.fc7", "linear + relu", shape, 2.0 * r * hidden_ * hidden_);
    row_predictor_ = prof->add("roi_heads.box_predictor", "linear (scores, deltas)", "", 2.0 * r * hidden_ * 5 * classes_);
    row_post_ = prof->add("roi_heads.postprocess", "softmax, decode, NMS, top-k", "", 0);
  }
  scales_.clear();
  for (const Shape& s : pooled) scales_.push_back(infer_scale(s.h, sizes.resized_h));
  k_min_ = static_cast<int>(-std::log2(scales_.front()));
  k_max_ = static_cast<int>(-std::log2(scales_.back()));
  const std::size_t rois = std::max(1, max_rois);
  features_.resize(rois * kChannels * kPool * kPool);
  h6_.resize(rois * hidden_);
  h7_.resize(rois * hidden_);
  logits_.resize(rois * 5 * classes_);
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
  rp.sampling_ratio = 2;
  rp.isa = fc6_.isa();
  Profiler::Scope t_pool(prof_, row_pool_);
  parallel_for(r, true, [&](long long i_) {
    const int i = static_cast<int>(i_);
    // LevelMapper in float32: floor(4 + log2(sqrt(area) / 224) + 1e-6), clamped.
    const Box& b = proposals[i];
    const float s = std::sqrt((b.x2 - b.x1) * (b.y2 - b.y1));
    float lvl = std::floor(4.0f + std::log2(s / 224.0f) + 1e-6f);
    // Written so that a NaN level (degenerate box) also lands on k_min, never out of range.
    lvl = lvl > static_cast<float>(k_min_) ? std::min(lvl, static_cast<float>(k_max_)) : static_cast<float>(k_min_);
    const int level = static_cast<int>(lvl) - k_min_;
    RoiAlignParams p = rp;
    p.spatial_scale = scales_[level];
    roi_align_one(pooled[level], 0, b, p, features_.data() + i * per_roi);
  });
  t_pool.stop();
  // y = act(x W^T + b) over the r RoIs, timed into profiler row `row`.
  auto linear = [&](int row, const float* x, int lda, const GemmWeights& w, const AlignedBuffer& b, Act act, float* y) {
    Profiler::Scope t(prof_, row);
    GemmEpilogue ep;
    ep.bias = b.data(), ep.act = act;
    gemm_parallel(r, x, lda, w, y, w.n(), ep);
  };
  const int c = classes_;
  linear(row_fc6_, features_.data(), static_cast<int>(per_roi), fc6_, fc6_bias_, Act::Relu, h6_.data());
  linear(row_fc7_, h6_.data(), hidden_, fc7_, fc7_bias_, Act::Relu, h7_.data());
  linear(row_predictor_, h7_.data(), hidden_, predictor_, predictor_bias_, Act::None, logits_.data());
  if (dump_) {
    dump_nhwc(dump_, pool_name_, ConstTensorView(features_.data(), Shape{r, kPool, kPool, kChannels}));
    dump_rows(dump_, head_name_, h7_.data(), r, hidden_, 0, hidden_, head_covers_);
    if (predictor_whole_) {  // with fewer classes in use, PyTorch's rows are longer
      dump_rows(dump_, cls_name_, logits_.data(), r, 5 * c, 0, c);
      dump_rows(dump_, box_name_, logits_.data(), r, 5 * c, c, 4 * c);
      dump_rows(dump_, pred0_name_, logits_.data(), r, 5 * c, 0, c);
      dump_rows(dump_, pred1_name_, logits_.data(), r, 5 * c, c, 4 * c);
    }
  }
  Profiler::Scope t_post(prof_, row_post_);

  boxes_.clear(), scores_.clear(), labels_.clear();
  const BoxCoderWeights weights{10.0f, 10.0f, 5.0f, 5.0f};
  float* prob = prob_.data();
  for (int i = 0; i < r; ++i) {
    const float* row = logits_.data() + static_cast<std::size_t>(i) * 5 * c;
    float mx = row[0];
    for (int k = 1; k < c; ++k) mx = std::max(mx, row[k]);
    float sum = 0;
    for (int k = 0; k < c; ++k) sum += (prob[k] = std::exp(row[k] - mx));
    for (int k = 0; k < c; ++k) prob[k] /= sum;
    for (int k = 1; k < c; ++k) {  // class 0 is background
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
