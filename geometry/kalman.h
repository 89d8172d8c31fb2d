// Scalar random-walk Kalman filter (F = H = 1, no control), as SHLE smooths the
// per-frame heights: x0 = first measurement, P0 given, then per measurement
//   P- = P + Q,  K = P- / (P- + R),  x = x + K (z - x),  P = (1 - K) P-.
// This equals cv::KalmanFilter with F = H = 1 and statePost/errorCovPost set to
// (z0, P0) before the first predict/correct pair.
#pragma once

#include <vector>

namespace geometry {

struct KalmanOptions {
  double q = 1e-3;  // process noise variance (released argparse default)
  double r = 1e-2;  // measurement noise variance
  double p0 = 6.0;  // initial state variance
};

class ScalarKalman {
 public:
  explicit ScalarKalman(const KalmanOptions& options = {}) : opt_(options) {}
  // Seeds the state with the first measurement (no filtering of z0 itself).
  void start(double z0);
  // Predict + correct with measurement z; returns the new state.
  double update(double z);
  bool started() const { return started_; }
  double state() const { return x_; }
  double variance() const { return p_; }

 private:
  KalmanOptions opt_;
  bool started_ = false;
  double x_ = 0, p_ = 0;
};

// The aligned ("correct") output: n values x0..x(n-1) for z0..z(n-1), x0 = z0.
std::vector<double> kalman_smooth(const std::vector<double>& z, const KalmanOptions& options);

// The released code's output with its off-by-one: n values x1..x(n-1) followed by
// 0.0 (z0 only seeds the state; value i is the estimate after measurement i+1).
std::vector<double> kalman_smooth_released(const std::vector<double>& z,
                                           const KalmanOptions& options);

}  // namespace geometry
