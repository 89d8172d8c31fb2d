#include <algorithm>
#include <cmath>

#include "shle/error.h"
#include "shle/tracker.h"

namespace shle {
namespace {

// Exact integer dot product of two rows; at most 32767 terms of 255 * 255 fit
// in 32 bits, and rows are split below that.
std::int64_t dot_row(const std::int16_t* a, const std::int16_t* b, int n) {
  std::int64_t total = 0;
  for (int start = 0; start < n; start += 32768) {
    int end = std::min(n, start + 32768);
    std::int32_t acc = 0;
    for (int i = start; i < end; ++i) acc += static_cast<std::int32_t>(a[i]) * b[i];
    total += acc;
  }
  return total;
}

}  // namespace

bool NccTracker::init(const GrayView& img, const Box& box) {
  ready_ = false;
  if (!box.finite() || img.width <= 0 || img.height <= 0 || !img.data) return false;
  // The released code seeds with the box truncated to int (x, y, w, h).
  double xd = std::trunc(box.x0), yd = std::trunc(box.y0);
  double wd = std::trunc(box.x1 - box.x0), hd = std::trunc(box.y1 - box.y0);
  double cx0 = std::max(xd, 0.0), cy0 = std::max(yd, 0.0);
  double cx1 = std::min(xd + wd, double(img.width)), cy1 = std::min(yd + hd, double(img.height));
  if (!(cx1 - cx0 >= 2) || !(cy1 - cy0 >= 2)) return false;
  // Patches of more than 10^7 pixels could overflow the exact 64-bit sums.
  if ((cx1 - cx0) * (cy1 - cy0) > 1e7) return false;
  x_ = static_cast<int>(cx0);
  y_ = static_cast<int>(cy0);
  w_ = static_cast<int>(cx1 - cx0);
  h_ = static_cast<int>(cy1 - cy0);
  tmpl_.resize(static_cast<std::size_t>(w_) * h_);
  std::int64_t s = 0, s2 = 0;
  for (int r = 0; r < h_; ++r)
    for (int c = 0; c < w_; ++c) {
      int v = img.data[static_cast<std::size_t>(y_ + r) * img.width + x_ + c];
      tmpl_[static_cast<std::size_t>(r) * w_ + c] = static_cast<std::int16_t>(v);
      s += v;
      s2 += v * v;
    }
  const std::int64_t n = static_cast<std::int64_t>(w_) * h_;
  sum_t_ = s;
  var_t_ = n * s2 - s * s;
  if (var_t_ <= 0) return false;
  ready_ = true;
  return true;
}

bool NccTracker::update(const GrayView& img, Box* box) {
  if (!ready_ || !img.data || img.width < w_ || img.height < h_) return false;
  const int R = opt_.search_radius;
  // Search region: every window whose top-left lies within R of the previous one.
  const int rx0 = std::max(0, x_ - R), ry0 = std::max(0, y_ - R);
  const int rx1 = std::min(img.width, x_ + R + w_), ry1 = std::min(img.height, y_ + R + h_);
  const int rw = rx1 - rx0, rh = ry1 - ry0;
  if (rw < w_ || rh < h_) return false;
  region_.resize(static_cast<std::size_t>(rw) * rh);
  integral_.assign(static_cast<std::size_t>(rw + 1) * (rh + 1), 0);
  integral_sq_.assign(static_cast<std::size_t>(rw + 1) * (rh + 1), 0);
  for (int r = 0; r < rh; ++r) {
    const std::uint8_t* src = img.data + static_cast<std::size_t>(ry0 + r) * img.width + rx0;
    std::int64_t row_s = 0, row_s2 = 0;
    std::int64_t* I = integral_.data() + static_cast<std::size_t>(r + 1) * (rw + 1);
    std::int64_t* I2 = integral_sq_.data() + static_cast<std::size_t>(r + 1) * (rw + 1);
    const std::int64_t* Ip = I - (rw + 1);
    const std::int64_t* I2p = I2 - (rw + 1);
    for (int c = 0; c < rw; ++c) {
      int v = src[c];
      region_[static_cast<std::size_t>(r) * rw + c] = static_cast<std::int16_t>(v);
      row_s += v;
      row_s2 += v * v;
      I[c + 1] = Ip[c + 1] + row_s;
      I2[c + 1] = I2p[c + 1] + row_s2;
    }
  }
  const std::int64_t n = static_cast<std::int64_t>(w_) * h_;
  const double var_t = static_cast<double>(var_t_);
  bool found = false;
  double best = 0;
  int bx = 0, by = 0;
  for (int dy = -R; dy <= R; ++dy) {
    const int ny = y_ + dy;
    if (ny < 0 || ny + h_ > img.height) continue;
    for (int dx = -R; dx <= R; ++dx) {
      if (dx * dx + dy * dy >= R * R && !(dx == 0 && dy == 0)) continue;
      const int nx = x_ + dx;
      if (nx < 0 || nx + w_ > img.width) continue;
      const int lx = nx - rx0, ly = ny - ry0;
      auto rect = [&](const std::vector<std::int64_t>& t) {
        const std::size_t s = rw + 1;
        return t[(ly + h_) * s + lx + w_] - t[ly * s + lx + w_] - t[(ly + h_) * s + lx] + t[ly * s + lx];
      };
      const std::int64_t si = rect(integral_), si2 = rect(integral_sq_);
      const std::int64_t var_i = n * si2 - si * si;
      if (var_i <= 0) continue;
      std::int64_t sit = 0;
      for (int r = 0; r < h_; ++r)
        sit += dot_row(region_.data() + static_cast<std::size_t>(ly + r) * rw + lx,
                       tmpl_.data() + static_cast<std::size_t>(r) * w_, w_);
      // n * sum(I T) - sum I * sum T = n^2 * covariance, exact in 64 bits since
      // n^2 * 255^2 < 2^63 for the patch sizes init() accepts.
      const double num = static_cast<double>(n * sit - si * sum_t_);
      const double score = num / std::sqrt(static_cast<double>(var_i) * var_t);
      if (!found || score > best) {
        found = true;
        best = score;
        bx = nx;
        by = ny;
      }
    }
  }
  if (!found) return false;
  last_score_ = best;
  if (best < opt_.min_score) return false;
  x_ = bx;
  y_ = by;
  *box = Box{double(bx), double(by), double(bx + w_), double(by + h_)};
  return true;
}


}  // namespace shle
