#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "geometry/error.h"
#include "geometry/kde.h"

namespace {

// The definition, evaluated in full on every grid point: first argmax of
// sum_k w_k exp(-(g - z_k)^2 / (2 h^2)), computed in log space (no underflow).
std::int64_t brute_force_mode(const std::vector<double>& z, double h, double step) {
  double zmax = 0;
  for (double v : z) zmax = std::max(zmax, v);
  std::int64_t last = static_cast<std::int64_t>(std::floor(zmax / step));
  std::vector<double> w(z.size(), 1.0);
  std::int64_t best = 0;
  double best_v = -INFINITY;
  for (std::int64_t j = 0; j <= last; ++j) {
    double v = geometry::gaussian_kde_log_density(z.data(), w.data(), z.size(), j * step, h);
    if (v > best_v) {
      best_v = v;
      best = j;
    }
  }
  return best;
}

TEST(Kde, MatchesBruteForceOnBarLikeData) {
  // The reference's illustration: 300 bar points at 30.3 +- 0.2 m and 500
  // background points uniform in 45..90 m: the mode is 30 m for h = 0.25, 1, 2.5.
  std::mt19937_64 rng(5);
  std::normal_distribution<double> bar(30.3, 0.2);
  std::uniform_real_distribution<double> bg(45, 90);
  std::vector<double> z;
  for (int i = 0; i < 300; ++i) z.push_back(bar(rng));
  for (int i = 0; i < 500; ++i) z.push_back(bg(rng));
  for (double h : {0.25, 1.0, 2.5}) {
    geometry::KdeOptions o;
    o.bandwidth = h;
    geometry::KdeMode m = geometry::gaussian_kde_mode(z, o);
    EXPECT_EQ(m.mode, 30.0) << h;
    EXPECT_EQ(m.grid_index, brute_force_mode(z, h, 1.0)) << h;
  }
}

TEST(Kde, MatchesBruteForceOnRandomSets) {
  std::mt19937_64 rng(17);
  for (int trial = 0; trial < 60; ++trial) {
    std::uniform_int_distribution<int> count(1, 400);
    std::uniform_real_distribution<double> centre(0.5, 120), spread(0.05, 30), u(0, 1);
    std::vector<double> z;
    int clusters = 1 + trial % 4;
    for (int c = 0; c < clusters; ++c) {
      double m = centre(rng), s = spread(rng);
      int n = count(rng);
      std::normal_distribution<double> d(m, s);
      for (int i = 0; i < n; ++i) z.push_back(std::max(0.0, d(rng)));
    }
    // Far, sparse outliers (sky mismatches) stretch the grid.
    if (trial % 3 == 0)
      for (int i = 0; i < 5; ++i) z.push_back(200 + 7000 * u(rng));
    geometry::KdeOptions o;
    o.bandwidth = trial % 2 ? 2.5 : 0.7;
    o.grid_step = trial % 5 == 0 ? 0.5 : 1.0;
    geometry::KdeMode m = geometry::gaussian_kde_mode(z, o);
    EXPECT_EQ(m.grid_index, brute_force_mode(z, o.bandwidth, o.grid_step)) << "trial " << trial;
    EXPECT_DOUBLE_EQ(m.mode, m.grid_index * o.grid_step);
  }
}

TEST(Kde, FirstMaximumWinsTies) {
  // One sample half-way between grid points 10 and 11: equal densities.
  geometry::KdeMode m = geometry::gaussian_kde_mode(std::vector<double>{10.5}, {});
  EXPECT_EQ(m.mode, 10.0);
  // Symmetric pair around 20.5.
  m = geometry::gaussian_kde_mode(std::vector<double>{19.8, 21.2}, {});
  EXPECT_EQ(m.mode, 20.0);
  // Symmetric pair around 30 (grid points 29 and 31 tie, 30 is higher).
  m = geometry::gaussian_kde_mode(std::vector<double>{29.0, 31.0}, {});
  EXPECT_EQ(m.mode, 30.0);
}

TEST(Kde, GridEndsAtFloorOfMax) {
  // All mass at 7.9: the grid is 0..7, so the mode is 7 (8 is not on the grid).
  geometry::KdeMode m = geometry::gaussian_kde_mode(std::vector<double>(50, 7.9), {});
  EXPECT_EQ(m.mode, 7.0);
  geometry::KdeOptions fine;
  fine.grid_step = 0.1;
  m = geometry::gaussian_kde_mode(std::vector<double>(50, 7.93), fine);
  EXPECT_NEAR(m.mode, 7.9, 1e-12);
}

TEST(Kde, WeightsEqualRepeatedSamples) {
  std::vector<double> repeated = {5, 5, 5, 9, 9, 14};
  std::vector<double> values = {5, 9, 14}, weights = {3, 2, 1};
  geometry::KdeMode a = geometry::gaussian_kde_mode(repeated, {});
  geometry::KdeMode b = geometry::gaussian_kde_mode(values.data(), weights.data(), 3, {});
  EXPECT_EQ(a.grid_index, b.grid_index);
  EXPECT_NEAR(a.density, b.density, 1e-12);
}

TEST(Kde, RejectsBadInput) {
  EXPECT_THROW(geometry::gaussian_kde_mode(std::vector<double>{}, {}), geometry::Error);
  EXPECT_THROW(geometry::gaussian_kde_mode(std::vector<double>{1.0, NAN}, {}), geometry::Error);
  EXPECT_THROW(geometry::gaussian_kde_mode(std::vector<double>{-1.0}, {}), geometry::Error);
  geometry::KdeOptions o;
  o.bandwidth = 0;
  EXPECT_THROW(geometry::gaussian_kde_mode(std::vector<double>{1.0}, o), geometry::Error);
  o.bandwidth = 2.5;
  o.grid_step = -1;
  EXPECT_THROW(geometry::gaussian_kde_mode(std::vector<double>{1.0}, o), geometry::Error);
  std::vector<double> unsorted = {3, 2}, w = {1, 1};
  EXPECT_THROW(geometry::gaussian_kde_mode(unsorted.data(), w.data(), 2, {}), geometry::Error);
  std::vector<double> sorted = {2, 3}, bad_w = {1, 0};
  EXPECT_THROW(geometry::gaussian_kde_mode(sorted.data(), bad_w.data(), 2, {}), geometry::Error);
  o.grid_step = 1e-300;
  EXPECT_THROW(geometry::gaussian_kde_mode(std::vector<double>{100.0}, o), geometry::Error);
}

// Issue 12, row 8: the grid's length (largest sample / step) is bounded before the
// loop: a step of 1e-9 m used to walk up to 2^52 grid points.
TEST(Kde, GridLongerThan2To26PointsIsRefusedAtOnce) {
  geometry::KdeOptions o;
  o.grid_step = 1e-9;
  try {
    geometry::gaussian_kde_mode(std::vector<double>{10.0, 12.0}, o);
    ADD_FAILURE() << "no error";
  } catch (const geometry::Error& e) {
    EXPECT_NE(std::string(e.what()).find("above the limit of 2^26 points"), std::string::npos) << e.what();
  }
  o.grid_step = 1.0;  // 2^26 exactly is allowed
  EXPECT_NO_THROW(geometry::gaussian_kde_mode(std::vector<double>{67108864.0}, o));
}

}  // namespace
