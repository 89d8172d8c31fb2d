#include "shle/height.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstring>

#include "shle/error.h"
#include "shle/height_rows.h"

namespace shle {
namespace {

// Depths beyond this (disparity below bf / 1e6 px) are treated as invalid: the
// released code would need a KDE grid of more than a million points for them.
constexpr double kMaxDepth = 1e6;

std::uint64_t double_bits(double f) {
  std::uint64_t u;
  std::memcpy(&u, &f, 8);
  return u;
}

double bits_double(std::uint64_t u) {
  double f;
  std::memcpy(&f, &u, 8);
  return f;
}

std::uint32_t slot_hash(std::uint64_t k, int shift) {
  return static_cast<std::uint32_t>((k * 0x9E3779B97F4A7C15ull) >> shift);
}

// Python's int() of a float: truncation towards zero. The argument is already
// clamped to the map, so it fits an int.
int trunc_index(double x) { return static_cast<int>(std::trunc(x)); }

}  // namespace

void validate(const HeightOptions& o) {
  auto finite_nonneg = [](double v) { return std::isfinite(v) && v >= 0; };
  if (!finite_nonneg(o.extend_top) || !finite_nonneg(o.extend_bottom))
    throw Error("box extension must be a finite number of pixels >= 0");
  if (std::isnan(o.min_height)) throw Error("height prefilter must be a number");
  if (!(o.bandwidth > 0) || !std::isfinite(o.bandwidth)) throw Error("KDE bandwidth must be > 0");
  if (!(o.grid_step >= kMinGridStep && o.grid_step <= kMaxGridStep))
    throw Error("KDE grid step must be a number in [0.001, 1000] metres (kMinGridStep, kMaxGridStep)");
  if (!(o.sigma > 0) || !std::isfinite(o.sigma)) throw Error("depth window sigma must be > 0");
  if (o.lowest_n < 1) throw Error("lowest N must be >= 1");
}

Box extend_and_clip(const Box& box, double extend_top, double extend_bottom, int width, int height) {
  Box e = box;
  e.y0 -= extend_top;
  e.y1 += extend_bottom;
  e.x0 = std::max(e.x0, 0.0);
  e.y0 = std::max(e.y0, 0.0);
  e.x1 = std::min(e.x1, static_cast<double>(width));
  e.y1 = std::min(e.y1, static_cast<double>(height));
  return e;
}

HeightEstimator::HeightEstimator(const Calibration& calibration, const HeightOptions& options)
    : cal_(calibration), opt_(options) {
  validate(opt_);
  // Scratch for a box as large as the calibrated image, touched now: growing it
  // later would put first-touch page faults (milliseconds) into some frame's time.
  // Capped at kPreallocatedPixels (a box is a fraction of the frame; larger boxes
  // grow the scratch on demand), so a huge calibrated size commits no memory.
  const std::size_t pixels = std::min<std::size_t>(
      static_cast<std::size_t>(std::max(cal_.width, 1)) * std::max(cal_.height, 1), kPreallocatedPixels);
  pts_.resize(pixels + 1);
  lowest_.resize(pixels + 1);
  row_z_.resize(cal_.width);
  row_y_.resize(cal_.width);
  row_keep_.resize(cal_.width);
}

void HeightEstimator::group_depths(std::size_t n) {
  // Open addressing on the depth's bit pattern (0 = empty: depths are positive);
  // equal disparities give bitwise equal depths. Boxes hold far fewer distinct
  // disparities than pixels, so the table starts small (cache resident) and
  // doubles at half load.
  std::size_t cap = 4096;
  int shift = 64 - 12;
  auto reset = [&](std::size_t c) {
    slots_.assign(c, Slot{0, 0});
  };
  if (slots_.size() != cap) reset(cap);
  used_slots_.clear();
  std::uint64_t last_key = 0;
  std::uint32_t last_slot = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint64_t k = double_bits(pts_[i].z);
    if (k == last_key) {  // neighbouring pixels often share a disparity
      ++slots_[last_slot].count;
      continue;
    }
    last_key = k;
    const std::uint32_t mask = static_cast<std::uint32_t>(cap - 1);
    std::uint32_t s = slot_hash(k, shift);
    while (slots_[s].key != 0 && slots_[s].key != k) s = (s + 1) & mask;
    if (slots_[s].key == 0) {
      slots_[s].key = k;
      used_slots_.push_back(s);
      if (2 * used_slots_.size() > cap) {
        ++slots_[s].count;
        last_key = 0;  // slots move
        std::vector<std::pair<std::uint64_t, std::uint32_t>> entries;
        entries.reserve(used_slots_.size());
        for (std::uint32_t t : used_slots_) entries.emplace_back(slots_[t].key, slots_[t].count);
        cap *= 2;
        --shift;
        reset(cap);
        used_slots_.clear();
        const std::uint32_t m2 = static_cast<std::uint32_t>(cap - 1);
        for (const auto& e : entries) {
          std::uint32_t t = slot_hash(e.first, shift);
          while (slots_[t].key != 0) t = (t + 1) & m2;
          slots_[t].key = e.first;
          slots_[t].count = e.second;
          used_slots_.push_back(t);
        }
        continue;
      }
    }
    ++slots_[s].count;
    last_slot = s;
  }
  distinct_.clear();
  for (std::uint32_t s : used_slots_) {
    distinct_.emplace_back(bits_double(slots_[s].key), slots_[s].count);
    slots_[s].key = 0;  // leave the table empty for the next frame
    slots_[s].count = 0;
  }
  std::sort(distinct_.begin(), distinct_.end());
  kde_z_.resize(distinct_.size());
  kde_w_.resize(distinct_.size());
  for (std::size_t i = 0; i < distinct_.size(); ++i) {
    kde_z_[i] = distinct_[i].first;
    kde_w_[i] = distinct_[i].second;
  }
}

HeightResult HeightEstimator::estimate(const DisparityMap& disp, const Box& box) {
  HeightResult r;
  if (!box.finite()) {
    r.problem = "box has non-finite coordinates";
    return r;
  }
  const int W = disp.width, H = disp.height;
  r.window = extend_and_clip(box, opt_.extend_top, opt_.extend_bottom, W, H);
  // A boxes CSV may hold x1 == x0 or y1 == y0: said plainly rather than as
  // "outside the map". A zero height still gets extend_top + extend_bottom rows,
  // as in the released code.
  if (!(box.x1 > box.x0) || !(box.y1 + opt_.extend_bottom > box.y0 - opt_.extend_top)) {
    r.problem = "box is empty (zero width, or zero height without extension)";
    return r;
  }
  const Box& e = r.window;
  r.u0 = trunc_index(std::min(e.x0, double(W)));
  r.v0 = trunc_index(std::min(e.y0, double(H)));
  r.u1 = std::max(trunc_index(std::max(e.x1, -1.0)), r.u0);
  r.v1 = std::max(trunc_index(std::max(e.y1, -1.0)), r.v0);
  if (r.u1 <= r.u0 || r.v1 <= r.v0) {
    r.problem = "box lies outside the " + std::to_string(W) + "x" + std::to_string(H) + " disparity map";
    r.u1 = r.u0;
    r.v1 = r.v0;
    return r;
  }

  const std::size_t cap = static_cast<std::size_t>(r.u1 - r.u0) * (r.v1 - r.v0);
  if (pts_.size() < cap + 1) pts_.resize(cap + 1);  // +1: the loop below stores before it decides
  const double bf = cal_.bf, fx = cal_.intrinsics.fx, fy = cal_.intrinsics.fy;
  const double cx = cal_.intrinsics.cx, cy = cal_.intrinsics.cy, mount = cal_.mount_height;
  const double neg_min_height = -opt_.min_height;
  std::size_t n = 0, valid = 0;
  if (!cal_.has_extrinsics) {
    // Level camera, the released arithmetic: Y = (v - cy) * Z / fy - mount.
    // Per row, first every pixel's Z and Y (independent divisions that pipeline
    // and vectorise), then a branch-free compaction: each pixel is stored at slot
    // n and n only advances for kept points (data-dependent branches mispredict).
    const int row_len = r.u1 - r.u0;
    if (row_z_.size() < static_cast<std::size_t>(row_len)) {
      row_z_.resize(row_len);
      row_y_.resize(row_len);
      row_keep_.resize(row_len);
    }
    Point* pts = pts_.data();
    double* rz = row_z_.data();
    double* ry = row_y_.data();
    std::int64_t* rk = row_keep_.data();
    const LevelRowFn row_kernel = level_row_kernel();
    for (int v = r.v0; v < r.v1; ++v) {
      const float* row = disp.d.data() + static_cast<std::size_t>(v) * W + r.u0;
      const double vc = static_cast<double>(v) - cy;
      row_kernel(row, row_len, RowParams{bf, vc, fy, mount, neg_min_height, kMaxDepth}, rz, ry, rk);
      for (int i = 0; i < row_len; ++i) {
        pts[n] = Point{rz[i], ry[i]};
        valid += rk[i] & 1;
        n += rk[i] >> 1;
      }
    }
  } else {
    const Eigen::Vector3d rrow = cal_.extrinsics.rotation.row(1).transpose();
    const double ty = cal_.extrinsics.translation.y();
    for (int v = r.v0; v < r.v1; ++v) {
      const float* row = disp.d.data() + static_cast<std::size_t>(v) * W;
      const double vc = static_cast<double>(v) - cy;
      for (int u = r.u0; u < r.u1; ++u) {
        const float d = row[u];
        if (!(d > 0.0f && d <= FLT_MAX)) continue;
        const double z = bf / static_cast<double>(d);
        if (!(z <= kMaxDepth)) continue;
        ++valid;
        const double xc = (static_cast<double>(u) - cx) * z / fx, yc = vc * z / fy;
        const double y = rrow.x() * xc + rrow.y() * yc + rrow.z() * z + ty;
        if (!(y < neg_min_height)) continue;
        pts_[n] = Point{z, y};
        ++n;
      }
    }
  }
  r.valid = valid;
  r.points = n;
  if (valid == 0) {
    // Say why: a map of NaN/Inf (a broken PFM, say) reads differently from one of
    // zeros (no stereo match). Counted only here, off the per-frame hot path.
    std::size_t non_finite = 0, total = 0;
    for (int v = r.v0; v < r.v1; ++v)
      for (int u = r.u0; u < r.u1; ++u, ++total) non_finite += !std::isfinite(disp.at(u, v));
    r.problem = "no valid disparity in the box";
    if (non_finite > 0)
      r.problem += " (" + std::to_string(non_finite) + " of its " + std::to_string(total) + " values are NaN or Inf)";
    return r;
  }
  if (n == 0) {
    r.problem = "no point above the " + std::to_string(opt_.min_height) + " m height prefilter";
    return r;
  }

  if (opt_.use_kde) {
    group_depths(n);
    geometry::KdeOptions ko;
    ko.bandwidth = opt_.bandwidth;
    ko.grid_step = opt_.grid_step;
    r.centre_depth = geometry::gaussian_kde_mode(kde_z_.data(), kde_w_.data(), kde_z_.size(), ko).mode;
  } else {
    double s = 0;
    for (std::size_t i = 0; i < n; ++i) s += pts_[i].z;
    r.centre_depth = s / static_cast<double>(n);
  }

  // Branch-free selection (as above): store at m, advance only inside the window.
  if (lowest_.size() < n + 1) lowest_.resize(n + 1);
  std::size_t m = 0;
  if (opt_.use_depth_window) {
    const double lo = r.centre_depth - opt_.sigma, hi = r.centre_depth + opt_.sigma;
    for (std::size_t i = 0; i < n; ++i) {
      lowest_[m] = pts_[i].y;
      m += (pts_[i].z > lo) & (pts_[i].z < hi);
    }
  } else {
    for (std::size_t i = 0; i < n; ++i) lowest_[i] = pts_[i].y;
    m = n;
  }
  r.window_points = m;
  if (m == 0) {
    r.problem = "no point in the depth window around " + std::to_string(r.centre_depth) + " m";
    return r;
  }
  // The N lowest points are those with the largest road Y (y points down).
  std::size_t take = std::min(m, static_cast<std::size_t>(opt_.lowest_n));
  std::nth_element(lowest_.begin(), lowest_.begin() + (take - 1), lowest_.begin() + m, std::greater<double>());
  std::sort(lowest_.begin(), lowest_.begin() + take, std::greater<double>());
  double sum = 0;
  for (std::size_t i = 0; i < take; ++i) sum += lowest_[i];
  r.height = std::fabs(sum / static_cast<double>(take));
  r.has_height = true;
  return r;
}

}  // namespace shle
