// LayerNorm kernels against a double-precision reference on every ISA; results
// independent of row grouping and thread count; argument errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "nn/error.h"
#include "nn/layernorm.h"
#include "nn/threads.h"
#include "tests/nn/isa_param.h"
#include "tests/nn/random_data.h"

namespace {

using nntest::random_vector;

class LayerNormTest : public testing::TestWithParam<nn::Isa> {};

// |y - ref| <= 1e-6 * (largest |ref| of the row): the float kernel against the
// double reference.
TEST_P(LayerNormTest, MatchesDoubleReference) {
  nntest::IsaScope scope(GetParam());
  const int cs[] = {1, 2, 5, 15, 16, 17, 33, 96, 100, 192, 384, 768};
  const std::size_t rows_list[] = {1, 2, 3, 4, 5, 7, 9, 13};
  struct Data { float offset, spread; };
  // Offsets far larger than the spread too: the mean correction keeps those accurate.
  const Data data[] = {{0.0f, 1.0f}, {1.0f, 1.0f}, {0.0f, 1000.0f}, {0.0f, 1e-3f}, {-2.0f, 3.0f},
                       {100.0f, 1.0f}, {-5.0f, 0.01f}};
  unsigned seed = 1;
  int case_index = 0;
  for (int c : cs)
    for (std::size_t rows : rows_list)
      for (const Data& d : data) {
        ++case_index;
        const bool affine = case_index % 3 != 0, beta_only = case_index % 5 == 0;
        const std::ptrdiff_t ldx = c + case_index % 4, ldy = c + case_index % 3;
        std::vector<float> x = random_vector(rows * ldx, seed++, -d.spread, d.spread);
        for (auto& v : x) v += d.offset;
        const std::vector<float> g = random_vector(c, seed++, 0.5f, 2.0f);
        const std::vector<float> b = random_vector(c, seed++, -1.0f, 1.0f);
        const float* gamma = affine && !beta_only ? g.data() : nullptr;
        const float* beta = affine ? b.data() : nullptr;
        const float eps = case_index % 2 ? 1e-6f : 1e-5f;
        std::vector<float> got(rows * ldy, -7.0f), want(rows * ldy, -7.0f);
        nn::layernorm(rows, c, x.data(), ldx, got.data(), ldy, gamma, beta, eps);
        nn::layernorm_ref(rows, c, x.data(), ldx, want.data(), ldy, gamma, beta, eps);
        for (std::size_t r = 0; r < rows; ++r) {
          float scale = 0.0f;
          for (int i = 0; i < c; ++i) scale = std::max(scale, std::fabs(want[r * ldy + i]));
          for (int i = 0; i < c; ++i)
            ASSERT_LE(std::fabs(got[r * ldy + i] - want[r * ldy + i]), 1e-6f * scale + 1e-30f)
                << "c " << c << " rows " << rows << " row " << r << " channel " << i
                << " offset " << d.offset << " spread " << d.spread;
          // Padding between rows is left alone.
          for (std::ptrdiff_t i = c; i < ldy; ++i) ASSERT_EQ(got[r * ldy + i], -7.0f);
        }
      }
}

TEST_P(LayerNormTest, InPlaceEqualsOutOfPlace) {
  nntest::IsaScope scope(GetParam());
  const int c = 100;
  const std::size_t rows = 11;
  std::vector<float> x = random_vector(rows * c, 3, -2.0f, 2.0f), y(rows * c);
  const std::vector<float> g = random_vector(c, 4, 0.5f, 2.0f), b = random_vector(c, 5, -1.0f, 1.0f);
  nn::layernorm(rows, c, x.data(), c, y.data(), c, g.data(), b.data(), 1e-6f);
  nn::layernorm(rows, c, x.data(), c, x.data(), c, g.data(), b.data(), 1e-6f);
  EXPECT_EQ(0, std::memcmp(x.data(), y.data(), x.size() * sizeof(float)));
}

// A row's bits must not depend on the rows processed with it (groups of four,
// padded last groups) nor on the thread split.
TEST_P(LayerNormTest, RowResultIndependentOfGroupingAndThreads) {
  nntest::IsaScope scope(GetParam());
  for (int c : {7, 96, 100, 768}) {
    const std::size_t rows = 1031;
    const std::vector<float> x = random_vector(rows * c, 9 + c, -3.0f, 5.0f);
    const std::vector<float> g = random_vector(c, 10, 0.5f, 2.0f), b = random_vector(c, 11, -1.0f, 1.0f);
    std::vector<float> all(rows * c), single(rows * c), shifted(rows * c), one(rows * c),
        two(rows * c);
    nn::layernorm(rows, c, x.data(), c, all.data(), c, g.data(), b.data(), 1e-6f);
    for (std::size_t r = 0; r < rows; ++r)
      nn::layernorm(1, c, x.data() + r * c, c, single.data() + r * c, c, g.data(), b.data(), 1e-6f);
    nn::layernorm(1, c, x.data(), c, shifted.data(), c, g.data(), b.data(), 1e-6f);
    nn::layernorm(rows - 1, c, x.data() + c, c, shifted.data() + c, c, g.data(), b.data(), 1e-6f);
    const int saved = nn::num_threads();
    nn::set_num_threads(1);
    nn::layernorm_parallel(rows, c, x.data(), c, one.data(), c, g.data(), b.data(), 1e-6f);
    nn::set_num_threads(2);
    nn::layernorm_parallel(rows, c, x.data(), c, two.data(), c, g.data(), b.data(), 1e-6f);
    nn::set_num_threads(saved);
    const std::size_t bytes = all.size() * sizeof(float);
    EXPECT_EQ(0, std::memcmp(all.data(), single.data(), bytes)) << "c " << c;
    EXPECT_EQ(0, std::memcmp(all.data(), shifted.data(), bytes)) << "c " << c;
    EXPECT_EQ(0, std::memcmp(all.data(), one.data(), bytes)) << "c " << c;
    EXPECT_EQ(0, std::memcmp(all.data(), two.data(), bytes)) << "c " << c;
  }
}

// Constant rows have zero variance: the output is beta (x - mean is exactly 0).
TEST_P(LayerNormTest, ConstantRowGivesBeta) {
  nntest::IsaScope scope(GetParam());
  const int c = 37;
  const std::vector<float> x(3 * c, 2.5f), g(c, 3.0f), b = random_vector(c, 1, -1.0f, 1.0f);
  std::vector<float> y(3 * c);
  nn::layernorm(3, c, x.data(), c, y.data(), c, g.data(), b.data(), 1e-5f);
  for (int r = 0; r < 3; ++r)
    for (int i = 0; i < c; ++i) EXPECT_EQ(y[r * c + i], b[i]);
}

INSTANTIATE_TEST_SUITE_P(Isa, LayerNormTest, testing::ValuesIn(nntest::supported_isas()),
                         nntest::isa_test_name);

TEST(LayerNormErrors, BadArgumentsThrow) {
  std::vector<float> x(64, 1.0f), y(64);
  EXPECT_THROW(nn::layernorm(2, 0, x.data(), 8, y.data(), 8, nullptr, nullptr, 1e-6f), nn::Error);
  EXPECT_THROW(nn::layernorm(2, 8, x.data(), 4, y.data(), 8, nullptr, nullptr, 1e-6f), nn::Error);
  EXPECT_THROW(nn::layernorm(2, 8, x.data(), 8, y.data(), 7, nullptr, nullptr, 1e-6f), nn::Error);
  EXPECT_THROW(nn::layernorm(2, 8, nullptr, 8, y.data(), 8, nullptr, nullptr, 1e-6f), nn::Error);
  EXPECT_THROW(nn::layernorm_parallel(2, 8, x.data(), 8, nullptr, 8, nullptr, nullptr, 1e-6f),
               nn::Error);
  EXPECT_THROW(nn::layernorm_ref(2, -1, x.data(), 8, y.data(), 8, nullptr, nullptr, 1e-6f),
               nn::Error);
  EXPECT_NO_THROW(nn::layernorm(0, 8, nullptr, 8, nullptr, 8, nullptr, nullptr, 1e-6f));
}

}  // namespace
