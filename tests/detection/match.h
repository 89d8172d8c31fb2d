// Matching our boxes against torchvision's: every reference box needs one of ours
// with IoU >= min_iou (and optionally a score within a tolerance), and vice versa.
#pragma once

#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "nn/models/detection/box_ops.h"

namespace dettest {

using nn::detection::Box;

inline std::vector<Box> to_boxes(const std::vector<float>& flat) {
  std::vector<Box> b(flat.size() / 4);
  for (std::size_t i = 0; i < b.size(); ++i) b[i] = {flat[4 * i], flat[4 * i + 1], flat[4 * i + 2], flat[4 * i + 3]};
  return b;
}

inline double iou(const Box& a, const Box& b) {
  const double w = std::max(0.0, double(std::min(a.x2, b.x2)) - std::max(a.x1, b.x1));
  const double h = std::max(0.0, double(std::min(a.y2, b.y2)) - std::max(a.y1, b.y1));
  const double inter = w * h;
  const double u = double(a.x2 - a.x1) * (a.y2 - a.y1) + double(b.x2 - b.x1) * (b.y2 - b.y1) - inter;
  return u > 0 ? inter / u : (inter == 0 && a.x1 == b.x1 && a.y1 == b.y1 && a.x2 == b.x2 && a.y2 == b.y2 ? 1 : 0);
}

struct MatchResult {
  std::size_t matched = 0, total = 0;
  std::string unmatched;  // the first few misses, for the test log
  double fraction() const { return total ? double(matched) / total : 1.0; }
};

// For each box of `from`, is there a box of `to` with IoU >= min_iou and (when scores
// are given) |score difference| <= score_tol and the same label?
inline MatchResult match(const std::vector<Box>& from, const std::vector<float>& from_scores,
                         const std::vector<std::int64_t>& from_labels, const std::vector<Box>& to,
                         const std::vector<float>& to_scores, const std::vector<std::int64_t>& to_labels,
                         double min_iou, double score_tol) {
  MatchResult r;
  r.total = from.size();
  std::ostringstream miss;
  int shown = 0;
  for (std::size_t i = 0; i < from.size(); ++i) {
    bool ok = false;
    for (std::size_t j = 0; j < to.size() && !ok; ++j) {
      if (!from_labels.empty() && from_labels[i] != to_labels[j]) continue;
      if (!from_scores.empty() && std::fabs(from_scores[i] - to_scores[j]) > score_tol) continue;
      ok = iou(from[i], to[j]) >= min_iou;
    }
    if (ok) {
      ++r.matched;
    } else if (shown++ < 8) {
      miss << " #" << i << " [" << from[i].x1 << "," << from[i].y1 << "," << from[i].x2 << "," << from[i].y2 << "]";
      if (!from_scores.empty()) miss << " score " << from_scores[i];
    }
  }
  r.unmatched = miss.str();
  return r;
}

}  // namespace dettest
