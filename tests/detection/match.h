// Matching our boxes against torchvision's: every reference box needs one of ours
// with IoU >= min_iou (and optionally a score within a tolerance), and vice versa.
#pragma once

#include <cmath>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

#include "nn/models/detection/box_ops.h"
#include "nn/models/detection/roi_heads.h"

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
  std::vector<std::size_t> missed;  // indexes into `from` of every miss
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
      continue;
    }
    r.missed.push_back(i);
    if (shown++ < 8) {
      miss << " #" << i << " [" << from[i].x1 << "," << from[i].y1 << "," << from[i].x2 << "," << from[i].y2 << "]";
      if (!from_scores.empty()) miss << " score " << from_scores[i];
    }
  }
  r.unmatched = miss.str();
  return r;
}

// Why a detection of one side can lack a partner on the other: its score sits within
// `tol` of a decision that float rounding can flip. That is the score threshold, the
// lowest score the other side kept (the top-n cut), or another detection of the same
// label with a different box (IoU < 0.99) and a score within tol on either side, so
// that NMS order between the two is a toss-up. Returns the misses none of these explain.
inline std::string unexplained_misses(const MatchResult& r, const std::vector<Box>& from,
                                      const std::vector<float>& from_scores,
                                      const std::vector<std::int64_t>& from_labels, const std::vector<Box>& to,
                                      const std::vector<float>& to_scores,
                                      const std::vector<std::int64_t>& to_labels, double score_thresh,
                                      double tol) {
  std::ostringstream out;
  for (std::size_t i : r.missed) {
    const double s = from_scores[i];
    bool explained = std::fabs(s - score_thresh) <= tol;
    if (!to_scores.empty()) {
      double lowest = to_scores[0];
      for (float t : to_scores) lowest = std::min(lowest, double(t));
      explained = explained || std::fabs(s - lowest) <= tol;
    }
    auto rival = [&](const std::vector<Box>& b, const std::vector<float>& sc, const std::vector<std::int64_t>& lb,
                     bool same_side) {
      for (std::size_t k = 0; k < b.size(); ++k) {
        if (same_side && k == i) continue;
        if (lb[k] == from_labels[i] && std::fabs(sc[k] - s) <= tol && iou(b[k], from[i]) < 0.99) return true;
      }
      return false;
    };
    explained = explained || rival(from, from_scores, from_labels, true) || rival(to, to_scores, to_labels, false);
    if (!explained)
      out << " #" << i << " [" << from[i].x1 << "," << from[i].y1 << "," << from[i].x2 << "," << from[i].y2
          << "] score " << s;
  }
  return out.str();
}

// Bitwise the same detections (boxes, scores, labels), e.g. for two thread counts.
inline bool identical(const nn::detection::Detections& a, const nn::detection::Detections& b) {
  return a.boxes.size() == b.boxes.size() && a.scores == b.scores && a.labels == b.labels &&
         (a.boxes.empty() || std::memcmp(a.boxes.data(), b.boxes.data(), a.boxes.size() * sizeof(Box)) == 0);
}

}  // namespace dettest
