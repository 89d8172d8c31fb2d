#include "nn/models/detection/box_ops.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace nn::detection {

Box decode_box(const Box& ref, const float* d, const BoxCoderWeights& w) {
  // Each line is one float32 tensor operation of decode_single, rounded as it is there.
  const float width = ref.x2 - ref.x1;
  const float height = ref.y2 - ref.y1;
  const float ctr_x = ref.x1 + 0.5f * width;
  const float ctr_y = ref.y1 + 0.5f * height;
  const float dx = d[0] / w.wx;
  const float dy = d[1] / w.wy;
  const float clip = static_cast<float>(kBoxXformClip);
  const float dw = std::min(d[2] / w.ww, clip);
  const float dh = std::min(d[3] / w.wh, clip);
  const float pcx = dx * width + ctr_x;
  const float pcy = dy * height + ctr_y;
  const float pw = std::exp(dw) * width;
  const float ph = std::exp(dh) * height;
  const float hw = 0.5f * pw;
  const float hh = 0.5f * ph;
  return {pcx - hw, pcy - hh, pcx + hw, pcy + hh};
}

Box clip_box(const Box& b, int height, int width) {
  const float w = static_cast<float>(width), h = static_cast<float>(height);
  auto c = [](float v, float hi) { return std::min(std::max(v, 0.0f), hi); };
  return {c(b.x1, w), c(b.y1, h), c(b.x2, w), c(b.y2, h)};
}

float box_iou(const Box& a, const Box& b) {
  const float area_a = (a.x2 - a.x1) * (a.y2 - a.y1);
  const float area_b = (b.x2 - b.x1) * (b.y2 - b.y1);
  const float w = std::max(0.0f, std::min(a.x2, b.x2) - std::max(a.x1, b.x1));
  const float h = std::max(0.0f, std::min(a.y2, b.y2) - std::max(a.y1, b.y1));
  const float inter = w * h;
  return inter / (area_a + area_b - inter);
}

void NmsWorkspace::reserve(std::size_t n) {
  for (auto* v : {&order, &members, &member_keep}) v->reserve(n);
  for (auto* v : {&areas, &member_scores}) v->reserve(n);
  suppressed.reserve(n);
  for (auto* v : {&shifted, &member_boxes}) v->reserve(n);
}

void top_k_descending(const float* scores, std::size_t n, std::size_t k, std::vector<int>& order) {
  order.resize(n);
  std::iota(order.begin(), order.end(), 0);
  k = std::min(k, n);
  auto before = [scores](int a, int b) { return score_before(scores, a, b); };
  // A strict total order, so selecting then sorting the first k equals a full stable sort's prefix.
  if (k < n) std::nth_element(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(k), order.end(), before);
  std::sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(k), before);
}

void nms(const std::vector<Box>& boxes, const std::vector<float>& scores, double iou_threshold, NmsWorkspace& ws,
         std::vector<int>& keep) {
  const std::size_t n = boxes.size();
  keep.clear();
  top_k_descending(scores.data(), n, n, ws.order);
  ws.areas.resize(n);
  for (std::size_t i = 0; i < n; ++i) ws.areas[i] = (boxes[i].x2 - boxes[i].x1) * (boxes[i].y2 - boxes[i].y1);
  ws.suppressed.assign(n, 0);
  const std::vector<int>& order = ws.order;
  for (std::size_t a = 0; a < n; ++a) {
    if (ws.suppressed[a]) continue;
    const int i = order[a];
    keep.push_back(i);
    const Box& bi = boxes[i];
    for (std::size_t b = a + 1; b < n; ++b) {
      if (ws.suppressed[b]) continue;
      const Box& bj = boxes[order[b]];
      const float w = std::max(0.0f, std::min(bi.x2, bj.x2) - std::max(bi.x1, bj.x1));
      const float h = std::max(0.0f, std::min(bi.y2, bj.y2) - std::max(bi.y1, bj.y1));
      const float inter = w * h;
      const float ovr = inter / (ws.areas[i] + ws.areas[order[b]] - inter);
      if (ovr > iou_threshold) ws.suppressed[b] = 1;
    }
  }
}

void batched_nms(const std::vector<Box>& boxes, const std::vector<float>& scores, const std::vector<int>& classes,
                 double iou_threshold, NmsWorkspace& ws, std::vector<int>& keep) {
  keep.clear();
  if (boxes.empty()) return;
  if (boxes.size() * 4 > 4000) {
    const int max_class = *std::max_element(classes.begin(), classes.end());
    for (int c = 0; c <= max_class; ++c) {
      ws.members.clear();
      for (std::size_t i = 0; i < boxes.size(); ++i)
        if (classes[i] == c) ws.members.push_back(static_cast<int>(i));
      if (ws.members.empty()) continue;
      ws.member_boxes.clear();
      ws.member_scores.clear();
      for (int i : ws.members) ws.member_boxes.push_back(boxes[i]), ws.member_scores.push_back(scores[i]);
      nms(ws.member_boxes, ws.member_scores, iou_threshold, ws, ws.member_keep);
      for (int k : ws.member_keep) keep.push_back(ws.members[k]);
    }
    // torchvision re-sorts the merged indices (ascending index order) by score, stably.
    std::sort(keep.begin(), keep.end(), [&](int a, int b) { return score_before(scores.data(), a, b); });
    return;
  }
  float max_coord = -INFINITY;
  for (const Box& b : boxes) max_coord = std::max({max_coord, b.x1, b.y1, b.x2, b.y2});
  const float step = max_coord + 1.0f;
  ws.shifted.resize(boxes.size());
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    const float off = static_cast<float>(classes[i]) * step;
    ws.shifted[i] = {boxes[i].x1 + off, boxes[i].y1 + off, boxes[i].x2 + off, boxes[i].y2 + off};
  }
  nms(ws.shifted, scores, iou_threshold, ws, keep);
}

std::vector<int> nms(const std::vector<Box>& boxes, const std::vector<float>& scores, double iou_threshold) {
  NmsWorkspace ws;
  std::vector<int> keep;
  nms(boxes, scores, iou_threshold, ws, keep);
  return keep;
}

std::vector<int> batched_nms(const std::vector<Box>& boxes, const std::vector<float>& scores,
                             const std::vector<int>& classes, double iou_threshold) {
  NmsWorkspace ws;
  std::vector<int> keep;
  batched_nms(boxes, scores, classes, iou_threshold, ws, keep);
  return keep;
}

}  // namespace nn::detection
