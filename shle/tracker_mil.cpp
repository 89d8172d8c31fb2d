// MIL tracker: the steps of OpenCV 4.6's TrackerMILImpl::init and ::update.
#include <algorithm>
#include <cmath>
#include <cstddef>

#include "shle/tracker.h"

namespace shle {
namespace {

// TrackerSamplerCSC's default maximum: every window within the radius is kept.
constexpr int kAllWindows = 1000000;
// The frames OpenCV integrates are BGR (cv2.imread); the tracker reads channel 0.
constexpr int kChannels = 3;
// Row sums of the float integral image are exact only below 2^24 (shle/mil_haar.h).
constexpr int kMaxWidth = (1 << 24) / 255;

bool usable(const GrayView& img) {
  return img.data && img.width > 0 && img.height > 0 && img.width <= kMaxWidth;
}

}  // namespace

MilTracker::MilTracker(const MilOptions& options)
    : opt_(options),
      rand_(options.rand_seed),
      lanes_(options.integral_lanes < 0 ? opencv_integral_lanes() : options.integral_lanes) {}

void MilTracker::features_of(const std::vector<MilWindow>& windows, std::vector<float>* values) const {
  const std::size_t nf = features_.size();
  values->resize(windows.size() * nf);
  for (std::size_t i = 0; i < windows.size(); ++i)
    for (std::size_t k = 0; k < nf; ++k)
      (*values)[i * nf + k] = haar_value(features_[k], ii_, windows[i].x, windows[i].y, w_, h_);
}

bool MilTracker::sample_training_windows() {
  // Radii in float as TrackerMIL::Params holds them.
  const float in_radius = static_cast<float>(opt_.init_radius);
  const float search = static_cast<float>(opt_.search_radius);
  mil_sample(ii_.height, ii_.width, x_, y_, w_, h_, in_radius, 0.0f, kAllWindows, &rng_, &pos_);
  mil_sample(ii_.height, ii_.width, x_, y_, w_, h_, 2.0f * search, 1.5f * in_radius, opt_.max_negatives, &rng_,
             &neg_);
  return !pos_.empty() && !neg_.empty();
}

void MilTracker::input_channel(const RgbImage& rgb, GrayImage* out) const {
  out->width = rgb.width;
  out->height = rgb.height;
  const std::size_t n = static_cast<std::size_t>(rgb.width) * rgb.height;
  out->px.resize(n);
  for (std::size_t i = 0; i < n; ++i) out->px[i] = rgb.rgb[3 * i + 2];
}

bool MilTracker::init(const GrayView& img, const Box& box) {
  ready_ = false;
  if (!box.finite() || !usable(img)) return false;
  // The released code seeds with the box truncated to int (x, y, w, h).
  const double xd = std::trunc(box.x0), yd = std::trunc(box.y0);
  const double wd = std::trunc(box.x1 - box.x0), hd = std::trunc(box.y1 - box.y0);
  if (!(std::fabs(xd) < 1e9 && std::fabs(yd) < 1e9 && wd >= 1 && hd >= 1 && wd < 1e9 && hd < 1e9)) return false;
  x_ = static_cast<int>(xd);
  y_ = static_cast<int>(yd);
  w_ = static_cast<int>(wd);
  h_ = static_cast<int>(hd);
  mil_integral(img, lanes_, kChannels, &ii_);
  // Each init makes a new sampler, a copy of the untouched cv::theRNG().
  rng_ = CvRng();
  // OpenCV samples first and asserts both sets are non-empty before it draws
  // the features, so a failed init leaves rand() where it was.
  if (!sample_training_windows()) return false;
  features_.resize(static_cast<std::size_t>(std::max(0, opt_.features)));
  for (HaarFeature& f : features_)
    if (!draw_haar_feature(w_, h_, &rand_, &f)) return false;  // OpenCV would loop forever
  if (features_.empty()) return false;
  boost_.reset(opt_.features, opt_.selected, static_cast<float>(opt_.learning_rate));
  features_of(pos_, &pos_values_);
  features_of(neg_, &neg_values_);
  boost_.update(pos_values_, static_cast<int>(pos_.size()), neg_values_, static_cast<int>(neg_.size()));
  ready_ = true;
  return true;
}

bool MilTracker::update(const GrayView& img, Box* box) {
  if (!ready_ || !usable(img)) return false;
  mil_integral(img, lanes_, kChannels, &ii_);
  mil_sample(ii_.height, ii_.width, x_, y_, w_, h_, static_cast<float>(opt_.search_radius), 0.0f, kAllWindows,
             &rng_, &detect_);
  if (detect_.empty()) return false;
  // Score = float sum of the chosen stumps; the first maximum wins (std::max_element).
  const std::vector<int>& sel = boost_.selected();
  chosen_.resize(sel.size());
  std::size_t best = 0;
  float best_score = 0;
  for (std::size_t i = 0; i < detect_.size(); ++i) {
    for (std::size_t k = 0; k < sel.size(); ++k)
      chosen_[k] = haar_value(features_[static_cast<std::size_t>(sel[k])], ii_, detect_[i].x, detect_[i].y, w_, h_);
    const float s = boost_.score(chosen_.data());
    if (i == 0 || best_score < s) {
      best = i;
      best_score = s;
    }
  }
  // The new position is kept even when the training below fails, as OpenCV's
  // trajectory keeps it.
  x_ = detect_[best].x;
  y_ = detect_[best].y;
  if (!sample_training_windows()) return false;
  features_of(pos_, &pos_values_);
  features_of(neg_, &neg_values_);
  boost_.update(pos_values_, static_cast<int>(pos_.size()), neg_values_, static_cast<int>(neg_.size()));
  *box = Box{double(x_), double(y_), double(x_) + w_, double(y_) + h_};
  return true;
}

}  // namespace shle
