// weights/tensor_compare: the tolerance rule, non-finite values, coordinates, and the
// network order of compare_files.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "weights/tensor_compare.h"

namespace {

using weights::compare_values;
using weights::Tolerance;

TEST(TensorCompare, TensorRuleScalesByMaxRef) {
  const std::vector<float> ref = {1, -4, 2, 0}, a = {1.003f, -4, 2, 0.003f};
  Tolerance t;
  t.rtol = 1e-3;  // allowed 0.004
  auto c = compare_values(a.data(), ref.data(), {2, 2}, t);
  EXPECT_TRUE(c.ok());
  EXPECT_NEAR(c.allowed, 0.004, 1e-12);
  EXPECT_DOUBLE_EQ(c.max_abs_ref, 4.0);
  EXPECT_EQ(c.worst, 0);  // 0.003 twice: the first wins
  t.per_element = true;   // element 3: 0.003 > 1e-3 * 0
  c = compare_values(a.data(), ref.data(), {2, 2}, t);
  EXPECT_EQ(c.failing, 2);
  EXPECT_EQ(c.first_failing, 0);
  t.atol = 0.01;
  EXPECT_TRUE(compare_values(a.data(), ref.data(), {2, 2}, t).ok());
}

TEST(TensorCompare, NonFiniteValues) {
  const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
  const std::vector<float> ref = {nan, inf, -inf, 1}, same = {nan, inf, -inf, 1}, other = {1, inf, inf, 1};
  Tolerance t;
  auto c = compare_values(same.data(), ref.data(), {4}, t);
  EXPECT_TRUE(c.ok());
  EXPECT_EQ(c.max_abs_diff, 0.0);
  EXPECT_EQ(c.ref_nan, 1);
  EXPECT_EQ(c.ref_inf, 2);
  EXPECT_DOUBLE_EQ(c.max_abs_ref, 1.0);
  c = compare_values(other.data(), ref.data(), {4}, t);
  EXPECT_EQ(c.failing, 2);
  EXPECT_TRUE(std::isinf(c.max_abs_diff));
  EXPECT_EQ(c.worst, 0);
  EXPECT_EQ(c.inf, 2);
}

TEST(TensorCompare, CoordinatesAndEmptyTensors) {
  EXPECT_EQ(weights::unravel_index(23, {2, 3, 4}), (std::vector<std::int64_t>{1, 2, 3}));
  EXPECT_EQ(weights::unravel_index(0, {}), (std::vector<std::int64_t>{}));
  EXPECT_EQ(weights::index_str({1, 2}), "[1, 2]");
  auto c = compare_values(static_cast<const float*>(nullptr), nullptr, {0, 5}, Tolerance{});
  EXPECT_TRUE(c.ok());
  EXPECT_EQ(c.count, 0);
  EXPECT_EQ(c.worst, -1);
  const float one = 1, two = 2;
  c = compare_values(&two, &one, {}, Tolerance{});  // a scalar
  EXPECT_FALSE(c.ok());
  EXPECT_TRUE(c.worst_coords.empty());
  EXPECT_DOUBLE_EQ(c.max_rel_diff, 1.0);
}

TEST(TensorCompare, FilesInNetworkOrderWithOneSidedTensors) {
  const float x[2] = {1, 2}, y[2] = {1, 3};
  weights::Writer a, ref;
  a.add_f32("b", {2}, y);
  a.add_f32("a", {2}, y);
  a.add_f32("only_a", {2}, x);
  ref.add_f32("a", {2}, x);
  ref.add_f32("b", {2}, x);
  ref.add_f32("only_ref", {2}, x);
  ref.set_metadata("dump.order", "b,missing,a");
  const auto fa = weights::SafeTensors::from_bytes(a.bytes(), "a");
  const auto fr = weights::SafeTensors::from_bytes(ref.bytes(), "ref");
  EXPECT_EQ(weights::network_order(fr), (std::vector<std::string>{"b", "a", "only_ref"}));
  const auto c = weights::compare_files(fa, fr, Tolerance{});
  ASSERT_EQ(c.tensors.size(), 4u);
  EXPECT_EQ(c.tensors[0].name, "b");
  EXPECT_EQ(c.tensors[1].name, "a");
  EXPECT_EQ(c.tensors[2].name, "only_ref");
  EXPECT_EQ(c.tensors[3].name, "only_a");
  EXPECT_EQ(c.first_failure, 0);
  EXPECT_EQ(c.failures, 2u);
  EXPECT_EQ(c.only_in_a, 1u);
  EXPECT_EQ(c.only_in_ref, 1u);
  EXPECT_EQ(c.order_source, "dump.order of ref");
  const auto filtered = weights::compare_files(fa, fr, Tolerance{}, [](const std::string& n) { return n == "a"; });
  ASSERT_EQ(filtered.tensors.size(), 1u);
  EXPECT_EQ(filtered.first_failure, 0);
}

}  // namespace
