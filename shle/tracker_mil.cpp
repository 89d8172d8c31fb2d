// MIL tracker: online multiple-instance boosting over random Haar features.
#include <algorithm>
#include <cmath>

#include "shle/tracker.h"

namespace shle {
namespace {

double sigmoid(double x) { return 1.0 / (1.0 + std::exp(-x)); }

}  // namespace

std::uint64_t MilTracker::next_random() {
  // splitmix64: a fixed, portable sequence per tracker and seeding.
  std::uint64_t z = (rng_ += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

double MilTracker::Stump::eval(double x) const {
  // Log-likelihood ratio of two Gaussians (positive vs negative class).
  double lp = -(x - mu_pos) * (x - mu_pos) / (2 * var_pos) - 0.5 * std::log(var_pos);
  double ln = -(x - mu_neg) * (x - mu_neg) / (2 * var_neg) - 0.5 * std::log(var_neg);
  return lp - ln;
}

void MilTracker::integral(const GrayView& img) {
  iw_ = img.width;
  ih_ = img.height;
  const std::size_t s = static_cast<std::size_t>(iw_) + 1;
  ii_.assign(s * (ih_ + 1), 0);
  for (int y = 0; y < ih_; ++y) {
    std::int64_t row = 0;
    for (int x = 0; x < iw_; ++x) {
      row += img.data[static_cast<std::size_t>(y) * iw_ + x];
      ii_[(y + 1) * s + x + 1] = ii_[y * s + x + 1] + row;
    }
  }
}

double MilTracker::feature_value(const Feature& f, int x, int y) const {
  const std::size_t s = static_cast<std::size_t>(iw_) + 1;
  double v = 0;
  for (const Rect& r : f.rects) {
    const int x0 = x + r.x, y0 = y + r.y, x1 = x0 + r.w, y1 = y0 + r.h;
    std::int64_t sum = ii_[y1 * s + x1] - ii_[y0 * s + x1] - ii_[y1 * s + x0] + ii_[y0 * s + x0];
    v += r.weight * static_cast<double>(sum);
  }
  return v;
}

// Windows keep one pixel of margin inside the image, as OpenCV's sampler does.
std::vector<std::pair<int, int>> MilTracker::positives(int x, int y, int cols, int rows) const {
  std::vector<std::pair<int, int>> out;
  const int r = static_cast<int>(std::ceil(opt_.init_radius));
  const double r2 = opt_.init_radius * opt_.init_radius;
  for (int dy = -r; dy <= r; ++dy)
    for (int dx = -r; dx <= r; ++dx) {
      int nx = x + dx, ny = y + dy;
      if (dx * dx + dy * dy >= r2 || nx < 0 || ny < 0 || nx > cols - w_ - 1 || ny > rows - h_ - 1) continue;
      out.emplace_back(nx, ny);
    }
  return out;
}

std::vector<std::pair<int, int>> MilTracker::negatives(int x, int y, int cols, int rows) {
  std::vector<std::pair<int, int>> out;
  const int R = static_cast<int>(opt_.negative_radius);
  const double inner2 = 1.5 * opt_.init_radius * 1.5 * opt_.init_radius, outer2 = opt_.negative_radius * opt_.negative_radius;
  const double keep = static_cast<double>(opt_.max_negatives) / ((2.0 * R + 1) * (2.0 * R + 1));
  for (int dy = -R; dy <= R; ++dy)
    for (int dx = -R; dx <= R; ++dx) {
      double d2 = double(dx) * dx + double(dy) * dy;
      int nx = x + dx, ny = y + dy;
      if (d2 < inner2 || d2 >= outer2 || nx < 0 || ny < 0 || nx > cols - w_ - 1 || ny > rows - h_ - 1) continue;
      if (static_cast<double>(next_random() >> 11) * (1.0 / 9007199254740992.0) < keep) out.emplace_back(nx, ny);
    }
  if (out.size() > static_cast<std::size_t>(opt_.max_negatives)) out.resize(opt_.max_negatives);
  return out;
}

void MilTracker::train(const std::vector<std::pair<int, int>>& pos, const std::vector<std::pair<int, int>>& neg) {
  const std::size_t nf = features_.size(), np = pos.size(), nn = neg.size();
  std::vector<double> fp(nf * np), fn(nf * nn);
  for (std::size_t k = 0; k < nf; ++k) {
    for (std::size_t i = 0; i < np; ++i) fp[k * np + i] = feature_value(features_[k], pos[i].first, pos[i].second);
    for (std::size_t i = 0; i < nn; ++i) fn[k * nn + i] = feature_value(features_[k], neg[i].first, neg[i].second);
  }
  const double lr = opt_.learning_rate;
  auto update = [lr](const double* v, std::size_t n, double* mu, double* var, bool* seen) {
    if (n == 0) return;
    double mean = 0;
    for (std::size_t i = 0; i < n; ++i) mean += v[i];
    mean /= n;
    if (!*seen) {
      double s = 0;
      for (std::size_t i = 0; i < n; ++i) s += (v[i] - mean) * (v[i] - mean);
      *mu = mean;
      *var = s / n + 1e-9;
      *seen = true;
      return;
    }
    *mu = lr * *mu + (1 - lr) * mean;
    double s = 0;
    for (std::size_t i = 0; i < n; ++i) s += (v[i] - *mu) * (v[i] - *mu);
    *var = lr * *var + (1 - lr) * (s / n);
  };
  for (std::size_t k = 0; k < nf; ++k) {
    Stump& st = stumps_[k];
    update(&fp[k * np], np, &st.mu_pos, &st.var_pos, &st.seen_pos);
    update(&fn[k * nn], nn, &st.mu_neg, &st.var_neg, &st.seen_neg);
  }
  // Stump outputs per sample, then greedy selection from scratch.
  std::vector<double> hp(nf * np), hn(nf * nn);
  for (std::size_t k = 0; k < nf; ++k) {
    for (std::size_t i = 0; i < np; ++i) hp[k * np + i] = stumps_[k].eval(fp[k * np + i]);
    for (std::size_t i = 0; i < nn; ++i) hn[k * nn + i] = stumps_[k].eval(fn[k * nn + i]);
  }
  std::vector<double> Hp(np, 0.0), Hn(nn, 0.0);
  std::vector<char> used(nf, 0);
  chosen_.clear();
  const std::size_t want = std::min<std::size_t>(opt_.selected, nf);
  for (std::size_t step = 0; step < want; ++step) {
    double best = INFINITY;
    std::size_t pick = nf;
    for (std::size_t k = 0; k < nf; ++k) {
      if (used[k]) continue;
      // All positives form one bag (noisy-OR); each negative is its own bag.
      double miss = 1.0;
      for (std::size_t i = 0; i < np; ++i) miss *= 1.0 - sigmoid(Hp[i] + hp[k * np + i]);
      double loss = np ? -std::log(1.0 - miss + 1e-5) / np : 0.0;
      for (std::size_t i = 0; i < nn; ++i) loss += -std::log(1.0 - sigmoid(Hn[i] + hn[k * nn + i]) + 1e-5) / nn;
      if (loss < best) {
        best = loss;
        pick = k;
      }
    }
    if (pick == nf) break;
    used[pick] = 1;
    chosen_.push_back(static_cast<int>(pick));
    for (std::size_t i = 0; i < np; ++i) Hp[i] += hp[pick * np + i];
    for (std::size_t i = 0; i < nn; ++i) Hn[i] += hn[pick * nn + i];
  }
}

bool MilTracker::init(const GrayView& img, const Box& box) {
  ready_ = false;
  if (!box.finite() || img.width <= 0 || img.height <= 0 || !img.data) return false;
  double xd = std::trunc(box.x0), yd = std::trunc(box.y0);
  double x1 = std::min(xd + std::trunc(box.x1 - box.x0), double(img.width) - 1);
  double y1 = std::min(yd + std::trunc(box.y1 - box.y0), double(img.height) - 1);
  xd = std::max(xd, 0.0);
  yd = std::max(yd, 0.0);
  if (!(x1 - xd >= 4) || !(y1 - yd >= 4)) return false;
  x_ = static_cast<int>(xd);
  y_ = static_cast<int>(yd);
  w_ = static_cast<int>(x1 - xd);
  h_ = static_cast<int>(y1 - yd);
  rng_ = opt_.seed + 0x1000193ull * ++inits_;
  // Random Haar features inside the w x h patch; a feature is redrawn until all
  // its rectangles lie strictly inside with an area of at least 9 pixels each.
  features_.assign(opt_.features, Feature{});
  for (Feature& f : features_) {
    for (int attempt = 0; attempt < 10000; ++attempt) {
      int type = static_cast<int>(next_random() % 5);
      int x = static_cast<int>(next_random() % w_), y = static_cast<int>(next_random() % h_);
      double u1 = (next_random() >> 11) * (1.0 / 9007199254740992.0);
      double u2 = (next_random() >> 11) * (1.0 / 9007199254740992.0);
      int bw = static_cast<int>((1 - std::sqrt(1 - u1)) * w_), bh = static_cast<int>((1 - std::sqrt(1 - u2)) * h_);
      std::vector<Rect> r;
      switch (type) {
        case 0: r = {{x, y, bw, bh, 1}, {x, y + bh, bw, bh, -1}}; break;
        case 1: r = {{x, y, bw, bh, 1}, {x + bw, y, bw, bh, -1}}; break;
        case 2: r = {{x, y, bw, bh, 1}, {x, y + bh, bw, 2 * bh, -2}, {x, y + 3 * bh, bw, bh, 1}}; break;
        case 3: r = {{x, y, bw, bh, 1}, {x + bw, y, 2 * bw, bh, -2}, {x + 3 * bw, y, bw, bh, 1}}; break;
        default:
          r = {{x, y, bw, bh, 1}, {x + bw, y, bw, bh, -1}, {x, y + bh, bw, bh, -1}, {x + bw, y + bh, bw, bh, 1}};
      }
      bool ok = bw * bh >= 9;
      for (const Rect& q : r) ok = ok && q.x + q.w < w_ && q.y + q.h < h_;
      if (!ok) continue;
      for (Rect& q : r) q.weight /= static_cast<double>(q.w) * q.h;
      f.rects = r;
      break;
    }
    if (f.rects.empty()) return false;  // patch too small for any feature
  }
  stumps_.assign(features_.size(), Stump{});
  integral(img);
  std::vector<std::pair<int, int>> pos = positives(x_, y_, img.width, img.height);
  std::vector<std::pair<int, int>> neg = negatives(x_, y_, img.width, img.height);
  if (pos.empty() || neg.empty()) return false;
  train(pos, neg);
  ready_ = !chosen_.empty();
  return ready_;
}

bool MilTracker::update(const GrayView& img, Box* box) {
  if (!ready_ || !img.data || img.width <= w_ + 1 || img.height <= h_ + 1) return false;
  integral(img);
  const int R = static_cast<int>(opt_.search_radius);
  const double r2 = opt_.search_radius * opt_.search_radius;
  bool found = false;
  double best = 0;
  int bx = x_, by = y_;
  for (int dy = -R; dy <= R; ++dy)
    for (int dx = -R; dx <= R; ++dx) {
      int nx = x_ + dx, ny = y_ + dy;
      if (double(dx) * dx + double(dy) * dy >= r2 || nx < 0 || ny < 0 || nx > img.width - w_ - 1 ||
          ny > img.height - h_ - 1)
        continue;
      double score = 0;
      for (int k : chosen_) score += stumps_[k].eval(feature_value(features_[k], nx, ny));
      if (!found || score > best) {
        found = true;
        best = score;
        bx = nx;
        by = ny;
      }
    }
  if (!found) return false;
  x_ = bx;
  y_ = by;
  std::vector<std::pair<int, int>> pos = positives(x_, y_, img.width, img.height);
  std::vector<std::pair<int, int>> neg = negatives(x_, y_, img.width, img.height);
  if (!pos.empty() && !neg.empty()) train(pos, neg);
  *box = Box{double(bx), double(by), double(bx + w_), double(by + h_)};
  return true;
}

}  // namespace shle
