// Box arithmetic of torchvision's detection models (ops/boxes.py, models/detection/
// _utils.py BoxCoder, csrc/ops/cpu/nms_kernel.cpp), in float32 with torchvision's
// operation order so decisions at thresholds come out the same.
#pragma once

#include <cstdint>
#include <vector>

namespace nn::detection {

struct Box {
  float x1 = 0, y1 = 0, x2 = 0, y2 = 0;
};

// ln(1000 / 16): torchvision's bbox_xform_clip, the cap on dw and dh before exp().
constexpr double kBoxXformClip = 4.135166556742356;

struct BoxCoderWeights {
  float wx = 1, wy = 1, ww = 1, wh = 1;
};

// BoxCoder.decode_single for one box: deltas (dx, dy, dw, dh) against `ref`.
Box decode_box(const Box& ref, const float* deltas, const BoxCoderWeights& w);

// clip_boxes_to_image: x to [0, width], y to [0, height].
Box clip_box(const Box& b, int height, int width);

// remove_small_boxes keeps a box when both sides are >= min_size.
inline bool box_big_enough(const Box& b, float min_size) {
  return (b.x2 - b.x1) >= min_size && (b.y2 - b.y1) >= min_size;
}

float box_iou(const Box& a, const Box& b);

// Scratch of the NMS functions below, grown on first use and reused: a model
// reserves it at plan time so forward passes do not allocate.
struct NmsWorkspace {
  std::vector<int> order, members, member_keep;
  std::vector<float> areas, member_scores;
  std::vector<char> suppressed;
  std::vector<Box> shifted, member_boxes;
  void reserve(std::size_t boxes);
};

// torchvision.ops.nms: indices kept, in descending score order. Sorting is stable
// (ties keep index order, as Debian's torch 1.13.1 build does; NaN scores sort
// first, as torch.sort puts them); a box is suppressed when its IoU with a kept
// one is strictly greater than iou_threshold. `keep` is overwritten.
void nms(const std::vector<Box>& boxes, const std::vector<float>& scores, double iou_threshold,
         NmsWorkspace& ws, std::vector<int>& keep);

// torchvision.ops.batched_nms, including its choice of path: more than 1000 boxes
// runs NMS per class and merges; otherwise boxes are offset by
// class * (max coordinate + 1) and one NMS runs (the offset changes IoU rounding, so
// the two paths are not interchangeable for exactness). `keep` is overwritten.
void batched_nms(const std::vector<Box>& boxes, const std::vector<float>& scores, const std::vector<int>& classes,
                 double iou_threshold, NmsWorkspace& ws, std::vector<int>& keep);

// Allocating conveniences of the two above, for tests and one-off use.
std::vector<int> nms(const std::vector<Box>& boxes, const std::vector<float>& scores, double iou_threshold);
std::vector<int> batched_nms(const std::vector<Box>& boxes, const std::vector<float>& scores,
                             const std::vector<int>& classes, double iou_threshold);

// The order of the stable descending sort of `scores` (NaN first), as a strict
// total order on indices: ties go to the lower index.
inline bool score_before(const float* scores, int a, int b) {
  const float sa = scores[a], sb = scores[b];
  const bool na = sa != sa, nb = sb != sb;
  if (na || nb) return na && nb ? a < b : na;
  return sa > sb || (sa == sb && a < b);
}

// The first min(k, n) indices of the stable descending order of scores[0..n), in
// that order, written to `order` (resized to n; only the first k are sorted).
// No allocation when `order` has the capacity.
void top_k_descending(const float* scores, std::size_t n, std::size_t k, std::vector<int>& order);

}  // namespace nn::detection
