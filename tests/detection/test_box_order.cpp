// The selection the RPN and NMS rely on: top_k_descending must equal the prefix of
// a stable descending sort (NaN first), whatever k, ties and NaNs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include "nn/models/detection/box_ops.h"

namespace {

namespace det = nn::detection;

std::vector<int> stable_order(const std::vector<float>& s) {
  std::vector<int> o(s.size());
  std::iota(o.begin(), o.end(), 0);
  std::stable_sort(o.begin(), o.end(), [&](int a, int b) {
    const bool na = std::isnan(s[a]), nb = std::isnan(s[b]);
    if (na != nb) return na;
    return !na && s[a] > s[b];
  });
  return o;
}

TEST(TopKDescending, EqualsStableSortPrefixWithTiesAndNaN) {
  std::mt19937 rng(7);
  for (std::size_t n : {0u, 1u, 2u, 17u, 1000u, 4099u}) {
    std::vector<float> s(n);
    // Few distinct values: many ties; a few NaNs and infinities.
    for (auto& v : s) v = static_cast<float>(rng() % 9) - 4.0f;
    for (std::size_t i = 0; i < n; i += 13) s[i] = NAN;
    for (std::size_t i = 5; i < n; i += 29) s[i] = (i % 2) ? INFINITY : -INFINITY;
    const std::vector<int> expected = stable_order(s);
    for (std::size_t k : {std::size_t{0}, std::size_t{1}, std::size_t{5}, n / 2, n, n + 3}) {
      std::vector<int> got;
      det::top_k_descending(s.data(), n, k, got);
      ASSERT_EQ(got.size(), n);
      const std::size_t m = std::min(k, n);
      EXPECT_TRUE(std::equal(expected.begin(), expected.begin() + m, got.begin())) << "n=" << n << " k=" << k;
    }
  }
}

TEST(TopKDescending, NoAllocationWithCapacity) {
  std::vector<float> s = {3, 1, 3, 2};
  std::vector<int> order;
  order.reserve(4);
  const int* before = order.data();
  det::top_k_descending(s.data(), s.size(), 2, order);
  EXPECT_EQ(order.data(), before);
  EXPECT_EQ(order[0], 0);
  EXPECT_EQ(order[1], 2);
}

// The workspace versions give what the allocating ones give, reused across calls of
// different sizes (stale scratch must not leak into a later call).
TEST(NmsWorkspace, ReuseMatchesFreshCalls) {
  std::mt19937 rng(3);
  det::NmsWorkspace ws;
  std::vector<int> keep;
  for (int round = 0; round < 6; ++round) {
    const std::size_t n = round % 2 ? 1500 : 40;  // both batched_nms paths
    std::vector<det::Box> boxes(n);
    std::vector<float> scores(n);
    std::vector<int> classes(n);
    for (std::size_t i = 0; i < n; ++i) {
      const float x = static_cast<float>(rng() % 200), y = static_cast<float>(rng() % 200);
      boxes[i] = {x, y, x + 5 + static_cast<float>(rng() % 40), y + 5 + static_cast<float>(rng() % 40)};
      scores[i] = static_cast<float>(rng() % 50) / 50.0f;
      classes[i] = static_cast<int>(rng() % 3);
    }
    det::batched_nms(boxes, scores, classes, 0.5, ws, keep);
    EXPECT_EQ(keep, det::batched_nms(boxes, scores, classes, 0.5)) << "round " << round;
    det::nms(boxes, scores, 0.3, ws, keep);
    EXPECT_EQ(keep, det::nms(boxes, scores, 0.3)) << "round " << round;
  }
}

}  // namespace
