#include "nn/models/detection/rpn.h"

#include <algorithm>
#include <cmath>

#include "nn/error.h"
#include "nn/models/detection/anchors.h"

namespace nn::detection {

namespace {

// The head's shared conv, objectness and delta layers under each layout's names.
struct HeadNames {
  std::string conv, cls, box;
};
HeadNames head_names(WeightLayout layout) {
  if (layout == WeightLayout::Detectron2) return {"conv.", "objectness_logits.", "anchor_deltas."};
  return {"conv.0.0.", "cls_logits.", "bbox_pred."};
}

}  // namespace

RpnConfig detectron2_rpn_config() {
  RpnConfig c;
  c.anchor_sizes = {{32}, {64}, {128}, {256}, {512}};
  c.strides = {4, 8, 16, 32, 64};
  c.round_anchors = false;
  c.sigmoid_scores = false;
  c.score_thresh = -INFINITY;
  c.drop_non_finite = true;
  c.min_size = 0.0f;
  c.min_size_exclusive = true;
  c.layout = WeightLayout::Detectron2;
  return c;
}

std::vector<weights::TensorSpec> Rpn::tensor_specs(const std::string& p, int a, WeightLayout layout) {
  const HeadNames n = head_names(layout);
  return {{p + n.conv + "weight", {256, 256, 3, 3}}, {p + n.conv + "bias", {256}},
          {p + n.cls + "weight", {a, 256, 1, 1}}, {p + n.cls + "bias", {a}},
          {p + n.box + "weight", {4 * a, 256, 1, 1}}, {p + n.box + "bias", {4 * a}}};
}

Rpn::Rpn(const weights::SafeTensors& st, const std::string& p, const RpnConfig& cfg) : cfg_(cfg), prefix_(p) {
  if (cfg.anchor_sizes.empty()) throw Error("RPN: no anchor sizes configured");
  a_ = static_cast<int>(cfg.anchor_sizes[0].size() * cfg.aspect_ratios.size());
  Conv2dParams cp;
  cp.cin = cp.cout = 256, cp.kh = cp.kw = 3, cp.pad_h = cp.pad_w = 1;
  const HeadNames n = head_names(cfg.layout);
  conv_ = load_conv(st, p + n.conv, cp);
  std::vector<float> w = st.f32(p + n.cls + "weight"), b = st.f32(p + n.cls + "bias");
  const auto bw = st.f32(p + n.box + "weight"), bb = st.f32(p + n.box + "bias");
  w.insert(w.end(), bw.begin(), bw.end());
  b.insert(b.end(), bb.begin(), bb.end());
  heads_ = GemmWeights::pack(w.data(), 5 * a_, 256);
  heads_bias_.resize(b.size());
  std::copy(b.begin(), b.end(), heads_bias_.data());
}

void Rpn::plan(const std::vector<Shape>& levels, const ImageSizes& sizes) {
  if (levels.size() != cfg_.anchor_sizes.size())
    throw Error("RPN: " + std::to_string(levels.size()) + " feature maps but anchor sizes for " +
                std::to_string(cfg_.anchor_sizes.size()));
  hidden_.resize(levels.size());
  head_out_.resize(levels.size());
  anchors_.clear();
  scratch_ = ConvScratch();
  std::size_t largest = 0, candidates = 0;
  names_.clear();
  for (std::size_t l = 0; l < levels.size(); ++l) {
    // The head runs once per level: call k of a module is "name#k" (k > 0).
    const std::string call = l ? "#" + std::to_string(l) : "";
    const std::string head = prefix_.substr(0, prefix_.size() - 1), k = std::to_string(l);
    const HeadNames n = head_names(cfg_.layout);
    const bool d2 = cfg_.layout == WeightLayout::Detectron2;  // its conv module applies the ReLU itself
    names_.push_back({prefix_ + "conv" + call,
                      d2 ? prefix_ + "conv" + call
                         : module_list(prefix_, {"conv.0" + call, "conv.0.0" + call, "conv.0.1" + call}),
                      prefix_ + n.cls.substr(0, n.cls.size() - 1) + call,
                      prefix_ + n.box.substr(0, n.box.size() - 1) + call, head + "[0][" + k + "]",
                      head + "[1][" + k + "]"});
    const Shape& s = levels[l];
    hidden_[l].resize({1, s.h, s.w, 256});
    head_out_[l].resize({1, s.h, s.w, 5 * a_});
    scratch_.require(conv_, s.w);
    const auto cell = cfg_.round_anchors ? cell_anchors(cfg_.anchor_sizes[l], cfg_.aspect_ratios)
                                         : cell_anchors_unrounded(cfg_.anchor_sizes[l], cfg_.aspect_ratios);
    if (static_cast<int>(cell.size()) != a_) throw Error("RPN: every level needs the same number of anchors");
    if (!cfg_.strides.empty() && cfg_.strides.size() != levels.size())
      throw Error("RPN: " + std::to_string(levels.size()) + " feature maps but strides for " +
                  std::to_string(cfg_.strides.size()));
    anchors_.push_back(cfg_.strides.empty()
                           ? grid_anchors(cell, s.h, s.w, sizes.padded_h, sizes.padded_w)
                           : grid_anchors_strided(cell, s.h, s.w, cfg_.strides[l], cfg_.strides[l]));
    const std::size_t count = static_cast<std::size_t>(s.h) * s.w * a_;
    largest = std::max(largest, count);
    candidates += std::min<std::size_t>(count, static_cast<std::size_t>(std::max(cfg_.pre_nms_top_n, 0)));
  }
  scratch_.allocate();
  level_logits_.reserve(largest);
  order_.reserve(largest);
  for (auto* v : {&logits_, &kept_scores_}) v->reserve(candidates);
  for (auto* v : {&level_of_, &kept_levels_, &keep_}) v->reserve(candidates);
  for (auto* v : {&boxes_, &kept_boxes_}) v->reserve(candidates);
  nms_.reserve(candidates);
  result_.boxes.reserve(candidates);
  result_.scores.reserve(candidates);
}

const Proposals& Rpn::forward(const std::vector<ConstTensorView>& levels, const ImageSizes& sizes) {
  boxes_.clear(), logits_.clear(), level_of_.clear();
  for (std::size_t l = 0; l < levels.size(); ++l) {
    conv2d(levels[l], conv_, hidden_[l].view(), scratch_.get(), Act::Relu);
    GemmEpilogue ep;
    ep.bias = heads_bias_.data();
    const int pixels = static_cast<int>(hidden_[l].cview().pixels());
    gemm_parallel(pixels, hidden_[l].data.data(), 256, heads_, head_out_[l].data.data(), 5 * a_, ep);
    if (dump_) {
      const LevelNames& nm = names_[l];
      const Shape hs = hidden_[l].shape;
      dump_nhwc(dump_, nm.conv, hidden_[l].cview(), nm.conv_covers);
      const float* o = head_out_[l].data.data();
      dump_nhwc_channels(dump_, nm.cls, o, hs, 5 * a_, 0, a_);
      dump_nhwc_channels(dump_, nm.box, o, hs, 5 * a_, a_, 4 * a_);
      dump_nhwc_channels(dump_, nm.head_cls, o, hs, 5 * a_, 0, a_);
      dump_nhwc_channels(dump_, nm.head_box, o, hs, 5 * a_, a_, 4 * a_);
    }
    // Candidates of this level in (y, x, a) order, the order torchvision flattens them.
    const float* out = head_out_[l].data.data();
    const std::size_t count = static_cast<std::size_t>(pixels) * a_;
    level_logits_.resize(count);
    for (int px = 0; px < pixels; ++px)
      for (int a = 0; a < a_; ++a) level_logits_[static_cast<std::size_t>(px) * a_ + a] = out[px * 5 * a_ + a];
    const std::size_t k = std::min<std::size_t>(static_cast<std::size_t>(std::max(cfg_.pre_nms_top_n, 0)), count);
    top_k_descending(level_logits_.data(), count, k, order_);
    for (std::size_t i = 0; i < k; ++i) {
      const int idx = order_[i];
      const int px = idx / a_, a = idx % a_;
      boxes_.push_back(decode_box(anchors_[l][idx], out + px * 5 * a_ + a_ + 4 * a, BoxCoderWeights{}));
      logits_.push_back(level_logits_[idx]);
      level_of_.push_back(static_cast<int>(l));
    }
  }
  kept_boxes_.clear(), kept_scores_.clear(), kept_levels_.clear();
  for (std::size_t i = 0; i < boxes_.size(); ++i) {
    const Box& raw = boxes_[i];
    if (cfg_.drop_non_finite && !(std::isfinite(raw.x1) && std::isfinite(raw.y1) && std::isfinite(raw.x2) &&
                                  std::isfinite(raw.y2) && std::isfinite(logits_[i])))
      continue;
    const float score = cfg_.sigmoid_scores ? 1.0f / (1.0f + std::exp(-logits_[i])) : logits_[i];
    const Box b = clip_box(raw, sizes.resized_h, sizes.resized_w);
    if (cfg_.min_size_exclusive ? !(b.x2 - b.x1 > cfg_.min_size && b.y2 - b.y1 > cfg_.min_size)
                                : !box_big_enough(b, cfg_.min_size))
      continue;
    if (!(score >= cfg_.score_thresh)) continue;
    kept_boxes_.push_back(b);
    kept_scores_.push_back(score);
    kept_levels_.push_back(level_of_[i]);
  }
  batched_nms(kept_boxes_, kept_scores_, kept_levels_, cfg_.nms_thresh, nms_, keep_);
  result_.boxes.clear(), result_.scores.clear();
  const std::size_t n = std::min<std::size_t>(keep_.size(), static_cast<std::size_t>(std::max(cfg_.post_nms_top_n, 0)));
  for (std::size_t i = 0; i < n; ++i) {
    result_.boxes.push_back(kept_boxes_[keep_[i]]);
    result_.scores.push_back(kept_scores_[keep_[i]]);
  }
  return result_;
}

}  // namespace nn::detection
