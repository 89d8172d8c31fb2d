// Trackers that fill the frames between two boxes: seeded on the box of the
// earlier frame, then moved frame by frame; the box size never changes and the
// position moves at most search_radius px per frame (dx^2 + dy^2 < r^2, as the
// OpenCV MIL tracker searches).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "shle/mil_boost.h"
#include "shle/mil_haar.h"
#include "shle/mil_random.h"
#include "shle/mil_sampler.h"
#include "shle/types.h"

namespace shle {

class Tracker {
 public:
  virtual ~Tracker() = default;
  virtual std::string name() const = 0;
  // Seeds on `box` in `image` (truncated to whole pixels; NCC also clips it to
  // the image). False when the box cannot be tracked (NCC: smaller than 2x2
  // inside the image or no texture; MIL: no window or Haar feature fits);
  // update() then fails until the next init.
  virtual bool init(const GrayView& image, const Box& box) = 0;
  // Finds the box in the next frame; false when lost or not seeded.
  virtual bool update(const GrayView& image, Box* box) = 0;
  // The single channel of an RGB frame this tracker should be given: luma
  // (to_gray) unless the tracker reproduces a program that reads another one.
  virtual void input_channel(const RgbImage& rgb, GrayImage* out) const { to_gray(rgb, out); }
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

// OpenCV 4.6's TrackerMIL::Params defaults, plus what OpenCV fixes inside.
struct MilOptions {
  double init_radius = 3.0;    // samplerInitInRadius: positives dx^2 + dy^2 < r^2 (the 5x5 block)
  double search_radius = 25;   // samplerSearchWinSize: detection within r, negatives below 2 r
  int max_negatives = 65;      // samplerInitMaxNegNum
  int features = 250;          // featureSetNumFeatures: random Haar features = weak classifiers
  int selected = 50;           // ClfMilBoost's numSel, chosen per update
  double learning_rate = 0.85; // ClfMilBoost's lRate (used as float)
  // The C library's rand() seed of the process OpenCV runs in: 1 when nothing
  // called srand() (Python, the released scripts). One MilTracker stands for
  // one such process: its seeds draw their features one after the other.
  std::uint32_t rand_seed = 1;
  // Block width of OpenCV's cv::integral SIMD path (see shle/mil_haar.h); -1 =
  // what OpenCV picks on this CPU (32 with AVX-512, 16 with AVX2), 0 = no blocks.
  int integral_lanes = -1;
};

// OpenCV 4.6's cv::TrackerMIL re-created operation by operation
// (../shared/reference/shle.md section 9 and modules/video/src/tracking/ in
// opencv/opencv 4.6): the float integral image of the single channel it is
// given, glibc rand() Haar features (shle/mil_haar.h), cv::RNG window sampling
// (shle/mil_sampler.h) and the float MILBoost classifier (shle/mil_boost.h).
// Fed channel 0 of the frames OpenCV sees (blue of a BGR image: input_channel()),
// it returns cv2.TrackerMIL's boxes exactly, including successive inits in one
// process.
// The box is truncated to int (x, y, w, h) and never clipped; its size never
// changes; it never reports a loss (as MIL), only failing when no window fits.
class MilTracker : public Tracker {
 public:
  explicit MilTracker(const MilOptions& options = {});
  std::string name() const override { return "mil"; }
  bool init(const GrayView& image, const Box& box) override;
  bool update(const GrayView& image, Box* box) override;
  // Blue: OpenCV's channel 0 of the BGR frames cv2.imread gives the released code.
  void input_channel(const RgbImage& rgb, GrayImage* out) const override;

 private:
  // Positives and negatives around (x_, y_) from the sampler's generator; false
  // when either set is empty.
  bool sample_training_windows();
  void features_of(const std::vector<MilWindow>& windows, std::vector<float>* values) const;

  MilOptions opt_;
  GlibcRand rand_;
  CvRng rng_;
  int lanes_ = 0;
  bool ready_ = false;
  int x_ = 0, y_ = 0, w_ = 0, h_ = 0;
  std::vector<HaarFeature> features_;
  MilBoost boost_;
  MilIntegral ii_;
  std::vector<MilWindow> pos_, neg_, detect_;
  std::vector<float> pos_values_, neg_values_, chosen_;
};

// "ncc", "mil" or "none" (nullptr: gaps stay without a box). Throws shle::Error otherwise.
std::unique_ptr<Tracker> make_tracker(const std::string& kind, const NccOptions& ncc,
                                      const MilOptions& mil = {});

}  // namespace shle
