#include <gtest/gtest.h>

#include <cmath>

#include "geometry/kalman.h"

namespace {

// The worked example of the reference (shle.md section 5.2).
TEST(Kalman, ReferenceExample) {
  std::vector<double> z = {2.9, 2.8, 2.95, 2.85, 2.9, 2.88};
  std::vector<double> aligned = geometry::kalman_smooth(z, {});
  std::vector<double> want = {2.9, 2.8002, 2.8786, 2.8676, 2.8782, 2.8787};
  ASSERT_EQ(aligned.size(), want.size());
  for (std::size_t i = 0; i < want.size(); ++i) EXPECT_NEAR(aligned[i], want[i], 5e-5) << i;
  std::vector<double> compat = geometry::kalman_smooth_released(z, {});
  std::vector<double> want_c = {2.8002, 2.8786, 2.8676, 2.8782, 2.8787, 0.0};
  ASSERT_EQ(compat.size(), want_c.size());
  for (std::size_t i = 0; i < want_c.size(); ++i) EXPECT_NEAR(compat[i], want_c[i], 5e-5) << i;
  EXPECT_EQ(compat.back(), 0.0);
}

// The recursion written out independently, with explicit P.
TEST(Kalman, MatchesHandRecursion) {
  geometry::KalmanOptions o;
  o.q = 2e-3;
  o.r = 5e-2;
  o.p0 = 3.0;
  std::vector<double> z;
  for (int i = 0; i < 40; ++i) z.push_back(3.0 + 0.1 * std::sin(i * 0.7) + 0.01 * i);
  std::vector<double> got = geometry::kalman_smooth(z, o);
  double x = z[0], p = o.p0;
  EXPECT_EQ(got[0], z[0]);
  for (std::size_t i = 1; i < z.size(); ++i) {
    double pp = p + o.q;
    double k = pp / (pp + o.r);
    x = x + k * (z[i] - x);
    p = (1 - k) * pp;
    EXPECT_EQ(got[i], x) << i;  // same operations, same order: bitwise
  }
}

TEST(Kalman, SteadyStateGain) {
  geometry::ScalarKalman f;
  f.start(1.0);
  for (int i = 0; i < 500; ++i) f.update(1.0);
  // P- = Q/2 + sqrt(Q^2/4 + Q R) ~ 3.70e-3, K ~ 0.270 (reference 5.1).
  double p_pred = f.variance() + 1e-3;
  EXPECT_NEAR(p_pred, 0.5e-3 + std::sqrt(0.25e-6 + 1e-5), 1e-9);
  EXPECT_NEAR(p_pred / (p_pred + 1e-2), 0.270, 1e-3);
}

TEST(Kalman, EdgeCases) {
  EXPECT_TRUE(geometry::kalman_smooth({}, {}).empty());
  EXPECT_TRUE(geometry::kalman_smooth_released({}, {}).empty());
  EXPECT_EQ(geometry::kalman_smooth({4.2}, {}), std::vector<double>{4.2});
  EXPECT_EQ(geometry::kalman_smooth_released({4.2}, {}), std::vector<double>{0.0});
}

}  // namespace
