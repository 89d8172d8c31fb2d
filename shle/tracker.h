// Trackers that fill the frames between two boxes: seeded on the box of the
// earlier frame, then moved frame by frame; the box size never changes and the
// position moves at most search_radius px per frame (dx^2 + dy^2 < r^2, as the
// OpenCV MIL tracker searches).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "shle/types.h"

namespace shle {

class Tracker {
 public:
  virtual ~Tracker() = default;
  virtual std::string name() const = 0;
  // Seeds on `box` in `image` (truncated to whole pixels and clipped to the
  // image). False when the box cannot be tracked (smaller than 2x2 inside the
  // image, or no texture); update() then fails until the next init.
  virtual bool init(const GrayView& image, const Box& box) = 0;
  // Finds the box in the next frame; false when lost or not seeded.
  virtual bool update(const GrayView& image, Box* box) = 0;
};

struct NccOptions {
  int search_radius = 25;
  // Lost when the best score is below this; the default -1 never fails (as MIL).
  double min_score = -1.0;
};

// Zero-mean normalised cross-correlation of the seed patch (kept fixed, not
// updated) against every window within the search radius of the previous
// position that lies inside the image; best score wins, first in row-major order
// on ties. Sums are exact 64-bit integers, so the result does not depend on the
// machine or the evaluation order. Windows without texture (zero variance) are
// never chosen.
class NccTracker : public Tracker {
 public:
  explicit NccTracker(const NccOptions& options = {}) : opt_(options) {}
  std::string name() const override { return "ncc"; }
  bool init(const GrayView& image, const Box& box) override;
  bool update(const GrayView& image, Box* box) override;
  double last_score() const { return last_score_; }

 private:
  NccOptions opt_;
  bool ready_ = false;
  int x_ = 0, y_ = 0, w_ = 0, h_ = 0;
  std::vector<std::int16_t> tmpl_;
  std::int64_t sum_t_ = 0, var_t_ = 0;  // sum T and n * sum T^2 - (sum T)^2
  double last_score_ = 0;
  std::vector<std::int16_t> region_;
  std::vector<std::int64_t> integral_, integral_sq_;
};

struct MilOptions {
  double init_radius = 3.0;    // positives: offsets with dx^2 + dy^2 < r^2 (the 5x5 block)
  double search_radius = 25;   // detection: offsets within this radius
  double negative_radius = 50; // negatives: annulus 1.5 init_radius .. this
  int max_negatives = 65;
  int features = 250;          // random Haar features = weak classifiers
  int selected = 50;           // chosen per update by MILBoost
  double learning_rate = 0.85;
  std::uint64_t seed = 0x4D494C;  // features and negatives (deterministic run to run)
};

// A port of the MIL tracker (Babenko et al.) as OpenCV 4.6 configures it
// (../shared/reference/shle.md section 9): online MILBoost over random Haar
// features on the single-channel integral image, positives from the 5x5 block
// around the box (one noisy-OR bag), random negatives from an annulus, detection
// by the best window within the search radius. Written from the algorithm's
// description: it follows OpenCV's parameters, not its random numbers, so the
// boxes are not bit-identical to cv::TrackerMIL. Never reports a loss (as MIL).
class MilTracker : public Tracker {
 public:
  explicit MilTracker(const MilOptions& options = {}) : opt_(options) {}
  std::string name() const override { return "mil"; }
  bool init(const GrayView& image, const Box& box) override;
  bool update(const GrayView& image, Box* box) override;

 private:
  struct Rect {
    int x, y, w, h;
    double weight;  // +-1 or -2, divided by the area
  };
  struct Feature {
    std::vector<Rect> rects;
  };
  struct Stump {
    double mu_pos = 0, var_pos = 1, mu_neg = 0, var_neg = 1;
    bool seen_pos = false, seen_neg = false;
    double eval(double x) const;
  };
  void integral(const GrayView& image);
  double feature_value(const Feature& f, int x, int y) const;
  std::vector<std::pair<int, int>> positives(int x, int y, int cols, int rows) const;
  std::vector<std::pair<int, int>> negatives(int x, int y, int cols, int rows);
  void train(const std::vector<std::pair<int, int>>& pos, const std::vector<std::pair<int, int>>& neg);
  std::uint64_t next_random();

  MilOptions opt_;
  bool ready_ = false;
  int x_ = 0, y_ = 0, w_ = 0, h_ = 0;
  int iw_ = 0, ih_ = 0;
  std::uint64_t rng_ = 0, inits_ = 0;
  std::vector<Feature> features_;
  std::vector<Stump> stumps_;
  std::vector<int> chosen_;
  std::vector<std::int64_t> ii_;  // (iw+1) x (ih+1) integral image
};

// "ncc", "mil" or "none" (nullptr: gaps stay without a box). Throws shle::Error otherwise.
std::unique_ptr<Tracker> make_tracker(const std::string& kind, const NccOptions& ncc,
                                      const MilOptions& mil = {});

}  // namespace shle
