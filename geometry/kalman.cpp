#include "geometry/kalman.h"

namespace geometry {

void ScalarKalman::start(double z0) {
  x_ = z0;
  p_ = opt_.p0;
  started_ = true;
}

double ScalarKalman::update(double z) {
  if (!started_) {
    start(z);
    return x_;
  }
  double p_pred = p_ + opt_.q;
  double k = p_pred / (p_pred + opt_.r);
  x_ = x_ + k * (z - x_);
  p_ = (1.0 - k) * p_pred;
  return x_;
}

std::vector<double> kalman_smooth(const std::vector<double>& z, const KalmanOptions& options) {
  std::vector<double> out;
  out.reserve(z.size());
  ScalarKalman f(options);
  for (double v : z) out.push_back(f.update(v));
  return out;
}

std::vector<double> kalman_smooth_released(const std::vector<double>& z,
                                           const KalmanOptions& options) {
  std::vector<double> aligned = kalman_smooth(z, options);
  std::vector<double> out;
  out.reserve(z.size());
  for (std::size_t i = 1; i < aligned.size(); ++i) out.push_back(aligned[i]);
  if (!z.empty()) out.push_back(0.0);
  return out;
}

}  // namespace geometry
