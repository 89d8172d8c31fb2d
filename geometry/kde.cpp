#include "geometry/kde.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "geometry/error.h"

namespace geometry {
namespace {

void check_options(const KdeOptions& o) {
  if (!(o.bandwidth > 0.0) || !std::isfinite(o.bandwidth))
    throw Error("KDE: bandwidth must be a positive finite number, got " + std::to_string(o.bandwidth));
  if (!(o.grid_step > 0.0) || !std::isfinite(o.grid_step))
    throw Error("KDE: grid step must be a positive finite number, got " + std::to_string(o.grid_step));
}

}  // namespace

KdeMode gaussian_kde_mode(const double* z, const double* w, std::size_t n, const KdeOptions& options) {
  check_options(options);
  if (n == 0) throw Error("KDE: no samples");
  double total = 0, w_max = 0;
  for (std::size_t k = 0; k < n; ++k) {
    if (!std::isfinite(z[k]) || z[k] < 0.0) throw Error("KDE: samples must be finite and >= 0");
    if (k > 0 && z[k] < z[k - 1]) throw Error("KDE: samples must be sorted ascending");
    if (!(w[k] > 0.0) || !std::isfinite(w[k])) throw Error("KDE: weights must be positive and finite");
    total += w[k];
    w_max = std::max(w_max, w[k]);
  }
  const double h = options.bandwidth, s = options.grid_step;
  const double last_pos = std::floor(z[n - 1] / s);
  if (last_pos > kMaxKdeGridPoints)
    throw Error("KDE: a grid of " + std::to_string(last_pos) + " points (largest sample " + std::to_string(z[n - 1]) +
                " / grid step " + std::to_string(s) + ") is above the limit of 2^26 points; use a coarser grid step");
  const std::int64_t last = static_cast<std::int64_t>(last_pos);
  const double two_h2 = 2.0 * h * h;
  // ln(2^60) = 41.59; the +1 absorbs rounding in the window tests below.
  const double reach = std::sqrt(s * s + two_h2 * (41.588830833596715 + std::log(total / w_max)) + 1.0);

  KdeMode best;
  bool have = false;
  std::size_t lo = 0, hi = 0;
  std::int64_t j = static_cast<std::int64_t>(std::max(0.0, std::ceil((z[0] - reach) / s)));
  while (j <= last) {
    const double g = static_cast<double>(j) * s;
    while (hi < n && z[hi] <= g + reach) ++hi;
    while (lo < hi && z[lo] < g - reach) ++lo;
    if (lo == hi) {
      if (hi == n) break;
      // Nothing within reach: jump to the first grid point the next sample reaches.
      double next = std::ceil((z[hi] - reach) / s);
      j = std::max(j + 1, static_cast<std::int64_t>(next));
      continue;
    }
    double sum = 0;
    for (std::size_t k = lo; k < hi; ++k) {
      double d = g - z[k];
      sum += w[k] * std::exp(-(d * d) / two_h2);
    }
    if (!have || sum > best.density) {  // strict: the first maximum wins ties
      best.density = sum;
      best.grid_index = j;
      best.mode = g;
      have = true;
    }
    ++j;
  }
  if (!have) throw Error("KDE: internal error, no grid point evaluated");
  return best;
}

KdeMode gaussian_kde_mode(std::vector<double> samples, const KdeOptions& options) {
  for (double v : samples)
    if (!std::isfinite(v)) throw Error("KDE: samples must be finite and >= 0");
  std::sort(samples.begin(), samples.end());
  std::vector<double> values, weights;
  for (double v : samples) {
    if (!values.empty() && values.back() == v) {
      weights.back() += 1.0;
    } else {
      values.push_back(v);
      weights.push_back(1.0);
    }
  }
  return gaussian_kde_mode(values.data(), weights.data(), values.size(), options);
}

double gaussian_kde_log_density(const double* z, const double* w, std::size_t n, double x,
                                double bandwidth) {
  if (n == 0) throw Error("KDE: no samples");
  const double two_h2 = 2.0 * bandwidth * bandwidth;
  double top = -INFINITY, total = 0;
  for (std::size_t k = 0; k < n; ++k) {
    double d = x - z[k];
    top = std::max(top, -(d * d) / two_h2 + std::log(w[k]));
    total += w[k];
  }
  double sum = 0;
  for (std::size_t k = 0; k < n; ++k) {
    double d = x - z[k];
    sum += std::exp(-(d * d) / two_h2 + std::log(w[k]) - top);
  }
  const double log_norm = 0.5 * std::log(2.0 * M_PI) + std::log(bandwidth);
  return top + std::log(sum) - std::log(total) - log_norm;
}

}  // namespace geometry
