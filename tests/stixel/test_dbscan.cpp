// Grid DBSCAN against a direct port of scikit-learn's O(n^2) algorithm
// (neighbourhoods by brute force, then sklearn's dbscan_inner expansion).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "stixel/dbscan.h"
#include "stixel/error.h"

using stixel::Point2;

namespace {

std::vector<int> dbscan_brute_force(const std::vector<Point2>& p, double eps, int min_samples) {
  const int n = static_cast<int>(p.size());
  const double eps2 = eps * eps;
  std::vector<std::vector<int>> nbr(n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double da = p[i].a - p[j].a, db = p[i].b - p[j].b;
      if (da * da + db * db <= eps2) nbr[i].push_back(j);
    }
  std::vector<char> core(n);
  for (int i = 0; i < n; ++i) core[i] = static_cast<int>(nbr[i].size()) >= min_samples;
  std::vector<int> labels(n, -1), stack;
  int label = 0;
  for (int start = 0; start < n; ++start) {
    if (labels[start] != -1 || !core[start]) continue;
    int i = start;
    for (;;) {
      if (labels[i] == -1) {
        labels[i] = label;
        if (core[i])
          for (int v : nbr[i])
            if (labels[v] == -1) stack.push_back(v);
      }
      if (stack.empty()) break;
      i = stack.back();
      stack.pop_back();
    }
    ++label;
  }
  return labels;
}

void expect_same(const std::vector<Point2>& pts, double eps, int m, const std::string& what) {
  const std::vector<int> ref = dbscan_brute_force(pts, eps, m);
  const std::vector<int> got = stixel::dbscan(pts, eps, m);
  ASSERT_EQ(got.size(), ref.size()) << what;
  int mismatches = 0;
  for (std::size_t i = 0; i < ref.size(); ++i)
    if (got[i] != ref[i] && mismatches++ < 5)
      ADD_FAILURE() << what << ": point " << i << " (" << pts[i].a << ", " << pts[i].b
                    << ") label " << got[i] << ", brute force " << ref[i];
  EXPECT_EQ(mismatches, 0) << what;
}

// Stixel-like top points: per column, candidates along the viewing ray.
std::vector<Point2> rays(int columns, int candidates, std::mt19937& rng) {
  std::uniform_real_distribution<double> jitter(-0.05, 0.05);
  std::vector<Point2> pts;
  for (int u = 0; u < columns; ++u)
    for (int n = 0; n < candidates; ++n) {
      const double d = 4.0 + 62.0 * std::tan(1.155 * n / (candidates - 1)) / std::tan(1.155);
      const double x = (u * 8.0 - 960.0) * d / 2000.0;
      pts.push_back({x + jitter(rng), d + jitter(rng)});
    }
  return pts;
}

}  // namespace

TEST(Dbscan, MatchesBruteForceOnRandomSets) {
  std::mt19937 rng(1234);
  for (int trial = 0; trial < 60; ++trial) {
    const int n = std::uniform_int_distribution<int>(0, 600)(rng);
    const double extent = std::uniform_real_distribution<double>(1.0, 60.0)(rng);
    std::uniform_real_distribution<double> coord(-extent, extent);
    std::vector<Point2> pts(n);
    for (auto& p : pts) p = {coord(rng), coord(rng) * 0.5 + 20.0};
    const int m = 1 + trial % 5;
    const double eps = trial % 3 == 0 ? 1.42 : std::uniform_real_distribution<double>(0.2, 4.0)(rng);
    expect_same(pts, eps, m, "trial " + std::to_string(trial));
  }
}

TEST(Dbscan, MatchesBruteForceOnBlobsWithDuplicates) {
  std::mt19937 rng(99);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<Point2> pts;
    std::normal_distribution<double> g(0.0, 0.8);
    std::uniform_real_distribution<double> centre(-30, 30);
    const int blobs = 1 + trial % 7;
    for (int b = 0; b < blobs; ++b) {
      const double ca = centre(rng), cb = centre(rng);
      for (int k = 0; k < 80; ++k) pts.push_back({ca + g(rng), cb + g(rng)});
    }
    for (int k = 0; k < 30; ++k) pts.push_back(pts[k * 7 % pts.size()]);  // exact duplicates
    std::shuffle(pts.begin(), pts.end(), rng);
    expect_same(pts, 1.42, 2 + trial % 4, "blobs " + std::to_string(trial));
  }
}

TEST(Dbscan, DistanceExactlyEpsIsANeighbour) {
  // A chain with spacing exactly eps: sklearn counts distance <= eps.
  std::vector<Point2> pts;
  for (int i = 0; i < 10; ++i) pts.push_back({i * 1.5, 0.0});
  std::vector<int> labels = stixel::dbscan(pts, 1.5, 2);
  for (int l : labels) EXPECT_EQ(l, 0);
  // Just over eps: every point is noise.
  labels = stixel::dbscan(pts, std::nextafter(1.5, 0.0), 2);
  for (int l : labels) EXPECT_EQ(l, -1);
  expect_same(pts, 1.5, 2, "chain");
  // A lattice with diagonals at exactly eps * sqrt(2) and sides at eps.
  pts.clear();
  for (int i = 0; i < 12; ++i)
    for (int j = 0; j < 12; ++j) pts.push_back({i * 1.42, j * 1.42});
  expect_same(pts, 1.42, 5, "lattice");
}

TEST(Dbscan, BorderPointJoinsTheLowestLabel) {
  // Two dense groups and one point at exactly eps from a core of each. With
  // min_samples 4 that point is not core (3 neighbours incl. itself), so it is a
  // border point of both clusters and takes the lower label: the cluster whose
  // lowest-index core comes first (here the group listed first, on the right).
  std::vector<Point2> q = {{3, 0},  {3.3, 0},  {3.3, 0.3},  {3.6, 0.1},   // label 0
                           {0, 0},  {-0.3, 0}, {-0.3, 0.3}, {-0.6, 0.1},  // label 1
                           {1.5, 0}};
  std::vector<int> labels = stixel::dbscan(q, 1.5, 4);
  EXPECT_EQ(labels[0], 0);
  EXPECT_EQ(labels[4], 1);
  EXPECT_EQ(labels[8], 0);
  expect_same(q, 1.5, 4, "shared border");
  // One step more of min_samples makes the groups' members non-core: all noise.
  labels = stixel::dbscan(q, 1.5, 6);
  for (int l : labels) EXPECT_EQ(l, -1);
}

TEST(Dbscan, FullFrameOfStixelsMatchesBruteForce) {
  std::mt19937 rng(7);
  std::vector<Point2> pts = rays(240, 64, rng);  // 15,360 points, like threshold 0
  expect_same(pts, 1.42, 2, "full frame");
  std::vector<Point2> sub;
  for (std::size_t i = 0; i < pts.size(); i += 7) sub.push_back(pts[i]);
  expect_same(sub, 1.42, 4, "sparse frame");
}

TEST(Dbscan, FarOutliersUseTheSparseGrid) {
  std::mt19937 rng(3);
  std::vector<Point2> pts = rays(30, 16, rng);
  pts.push_back({1e7, -1e7});
  pts.push_back({1e7 + 1.0, -1e7});
  pts.push_back({-5e6, 3e6});
  expect_same(pts, 1.42, 2, "outliers");
  const std::vector<int> labels = stixel::dbscan(pts, 1.42, 2);
  EXPECT_EQ(labels[pts.size() - 3], labels[pts.size() - 2]);
  EXPECT_GE(labels[pts.size() - 3], 0);
  EXPECT_EQ(labels.back(), -1);
}

TEST(Dbscan, EdgeCasesAndErrors) {
  EXPECT_TRUE(stixel::dbscan({}, 1.42, 2).empty());
  EXPECT_EQ(stixel::dbscan({{1, 2}}, 1.42, 2), std::vector<int>{-1});
  EXPECT_EQ(stixel::dbscan({{1, 2}}, 1.42, 1), std::vector<int>{0});
  EXPECT_THROW(stixel::dbscan({{0, 0}}, 0.0, 2), stixel::Error);
  EXPECT_THROW(stixel::dbscan({{0, 0}}, NAN, 2), stixel::Error);
  EXPECT_THROW(stixel::dbscan({{0, 0}}, 1.0, 0), stixel::Error);
  EXPECT_THROW(stixel::dbscan({{0, NAN}}, 1.0, 2), stixel::Error);
  EXPECT_THROW(stixel::dbscan({{INFINITY, 0}}, 1.0, 2), stixel::Error);
}
