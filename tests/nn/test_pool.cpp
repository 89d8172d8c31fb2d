// Pooling ops: PyTorch's arithmetic (values produced by torch 1.13 embedded),
// naive loops on awkward shapes, NaN and padding behaviour, argument errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "nn/error.h"
#include "nn/pool.h"
#include "nn/threads.h"

#include "tests/nn/random_data.h"

namespace {

using nntest::random_vector;
using nn::Shape;

TEST(MeanOverRows, SumsRowsInOrderThenDividesLikeAvgPool2d) {
  // F.avg_pool2d(x, (3, 1)) on rows [1e8, 0.1, 3], [1, 0.2, 1e-8], [-1e8, 0.3, -3]
  // gives [0, 0.2, 0]: a float sum in row order (a pairwise or double sum would not).
  const std::vector<float> x = {1e8f, 0.1f, 3.0f, 1.0f, 0.2f, 1e-8f, -1e8f, 0.3f, -3.0f};
  std::vector<float> y(3, -1.0f);
  nn::mean_over_rows(nn::ConstTensorView(x.data(), Shape{1, 3, 3, 1}),
                     nn::TensorView{y.data(), Shape{1, 1, 3, 1}});
  EXPECT_EQ(y[0], 0.0f);
  EXPECT_EQ(y[1], 0.200000003f);
  EXPECT_EQ(y[2], 0.0f);
}

TEST(MeanOverRows, MatchesSequentialSumOnAwkwardShapes) {
  for (const Shape& s : {Shape{2, 1, 1, 1}, Shape{2, 7, 13, 17}, Shape{1, 40, 61, 100},
                         Shape{3, 9, 300, 33}}) {
    const std::vector<float> x = random_vector(s.count(), s.h * 7 + s.c, -3.0f, 4.0f);
    std::vector<float> y(static_cast<std::size_t>(s.n) * s.w * s.c);
    for (int threads : {1, 2}) {
      const int saved = nn::num_threads();
      nn::set_num_threads(threads);
      nn::mean_over_rows(nn::ConstTensorView(x.data(), s), nn::TensorView{y.data(), Shape{s.n, 1, s.w, s.c}});
      nn::set_num_threads(saved);
      for (int n = 0; n < s.n; ++n)
        for (int i = 0; i < s.w * s.c; ++i) {
          float sum = 0.0f;
          for (int r = 0; r < s.h; ++r) sum += x[(static_cast<std::size_t>(n) * s.h + r) * s.w * s.c + i];
          ASSERT_EQ(y[static_cast<std::size_t>(n) * s.w * s.c + i], sum / static_cast<float>(s.h))
              << "threads " << threads << " n " << n << " i " << i;
        }
    }
  }
}

float naive_max(const std::vector<float>& x, const Shape& s, const nn::MaxPoolParams& p, int n,
                int oy, int ox, int ch) {
  float m = -std::numeric_limits<float>::infinity();
  for (int ky = 0; ky < p.kh; ++ky)
    for (int kx = 0; kx < p.kw; ++kx) {
      const int y = oy * p.stride_h - p.pad_h + ky, xx = ox * p.stride_w - p.pad_w + kx;
      if (y < 0 || y >= s.h || xx < 0 || xx >= s.w) continue;
      const float v = x[((static_cast<std::size_t>(n) * s.h + y) * s.w + xx) * s.c + ch];
      if (std::isnan(v)) return v;
      m = std::max(m, v);
    }
  return m;
}

nn::MaxPoolParams pool(int k, int s, int p) {
  nn::MaxPoolParams m;
  m.kh = m.kw = k;
  m.stride_h = m.stride_w = s;
  m.pad_h = m.pad_w = p;
  return m;
}

TEST(MaxPool2d, MatchesNaiveLoops) {
  // ResNet's stem pool, FPN's LastLevelMaxPool, and asymmetric ones.
  nn::MaxPoolParams asym;
  asym.kh = 2;
  asym.kw = 3;
  asym.stride_h = 1;
  asym.stride_w = 2;
  asym.pad_h = 1;
  asym.pad_w = 0;
  for (const nn::MaxPoolParams& p : {pool(3, 2, 1), pool(1, 2, 0), pool(2, 2, 0), asym}) {
    for (const Shape& s : {Shape{2, 1, 1, 3}, Shape{2, 7, 13, 17}, Shape{1, 9, 29, 64}, Shape{2, 2, 6, 5}}) {
      if (s.h + 2 * p.pad_h < p.kh || s.w + 2 * p.pad_w < p.kw) continue;
      const nn::Shape os = nn::max_pool2d_output_shape(s, p);
      const std::vector<float> x = random_vector(s.count(), s.w + s.c, -3.0f, 4.0f);
      std::vector<float> y(os.count());
      nn::max_pool2d(nn::ConstTensorView(x.data(), s), p, nn::TensorView{y.data(), os});
      EXPECT_EQ(os.h, (s.h + 2 * p.pad_h - p.kh) / p.stride_h + 1);
      EXPECT_EQ(os.w, (s.w + 2 * p.pad_w - p.kw) / p.stride_w + 1);
      for (int n = 0; n < os.n; ++n)
        for (int oy = 0; oy < os.h; ++oy)
          for (int ox = 0; ox < os.w; ++ox)
            for (int ch = 0; ch < os.c; ++ch)
              ASSERT_EQ(y[((static_cast<std::size_t>(n) * os.h + oy) * os.w + ox) * os.c + ch],
                        naive_max(x, s, p, n, oy, ox, ch));
    }
  }
}

TEST(MaxPool2d, NaNPropagatesAndPaddingNeverWins) {
  // All inputs negative: -inf padding must never be the maximum.
  const Shape s{1, 4, 4, 2};
  std::vector<float> x(s.count(), -5.0f);
  x[1] = std::nanf("");  // pixel (0,0), channel 1
  const nn::MaxPoolParams p = pool(3, 2, 1);
  const Shape os = nn::max_pool2d_output_shape(s, p);
  std::vector<float> y(os.count());
  nn::max_pool2d(nn::ConstTensorView(x.data(), s), p, nn::TensorView{y.data(), os});
  for (int i = 0; i < os.h * os.w; ++i) {
    EXPECT_EQ(y[i * 2], -5.0f);
    // Only the first window (rows and columns -1..1) contains pixel (0,0).
    EXPECT_EQ(std::isnan(y[i * 2 + 1]), i == 0) << i;
  }
}

TEST(MaxPool2d, BadParametersThrow) {
  const Shape s{1, 8, 8, 4};
  EXPECT_THROW(nn::max_pool2d_output_shape(s, pool(3, 2, 2)), nn::Error);  // pad > k/2
  EXPECT_THROW(nn::max_pool2d_output_shape(s, pool(0, 2, 0)), nn::Error);
  EXPECT_THROW(nn::max_pool2d_output_shape(s, pool(3, 0, 1)), nn::Error);
  EXPECT_THROW(nn::max_pool2d_output_shape(Shape{1, 2, 2, 4}, pool(3, 1, 0)), nn::Error);
  std::vector<float> x(s.count()), y(s.count());
  EXPECT_THROW(nn::max_pool2d(nn::ConstTensorView(x.data(), s), pool(3, 2, 1),
                              nn::TensorView{y.data(), Shape{1, 3, 4, 4}}),
               nn::Error);
  EXPECT_THROW(nn::max_pool2d(nn::ConstTensorView(x.data(), s), pool(1, 1, 0),
                              nn::TensorView{x.data(), s}),
               nn::Error);
}

TEST(GlobalAvgPool, WithinHalfAnUlpOfTheExactMeanAndThreadCountIndependent) {
  for (const Shape& s : {Shape{2, 1, 1, 5}, Shape{2, 7, 13, 17}, Shape{1, 23, 40, 960}, Shape{3, 2, 3, 300},
                         Shape{1, 96, 168, 72}, Shape{2, 9, 11, 1100}}) {
    const std::vector<float> x = random_vector(s.count(), s.c, -3.0f, 4.0f);
    std::vector<float> y(static_cast<std::size_t>(s.n) * s.c), first;
    for (int threads : {1, 2, 3}) {
      const int saved = nn::num_threads();
      nn::set_num_threads(threads);
      nn::global_avg_pool(nn::ConstTensorView(x.data(), s), nn::TensorView{y.data(), Shape{s.n, 1, 1, s.c}});
      nn::set_num_threads(saved);
      for (int n = 0; n < s.n; ++n)
        for (int ch = 0; ch < s.c; ++ch) {
          long double sum = 0;
          for (int p = 0; p < s.h * s.w; ++p)
            sum += x[(static_cast<std::size_t>(n) * s.h * s.w + p) * s.c + ch];
          const long double mean = sum / (s.h * s.w);
          const float got = y[static_cast<std::size_t>(n) * s.c + ch];
          ASSERT_LE(std::fabs(static_cast<long double>(got) - mean),
                    std::fabs(mean) * 6e-8L + 1e-30L)
              << "n " << n << " ch " << ch;
        }
      if (first.empty()) first = y;
      EXPECT_EQ(0, std::memcmp(first.data(), y.data(), y.size() * sizeof(float))) << threads << " threads";
    }
  }
}

TEST(GlobalAvgPool, BadShapesThrow) {
  std::vector<float> x(2 * 3 * 4 * 5), y(10);
  EXPECT_THROW(nn::global_avg_pool(nn::ConstTensorView(x.data(), Shape{2, 3, 4, 5}),
                                   nn::TensorView{y.data(), Shape{2, 1, 1, 4}}),
               nn::Error);
  EXPECT_THROW(nn::global_avg_pool_shape(Shape{2, 0, 4, 5}), nn::Error);
  EXPECT_THROW(nn::mean_over_rows(nn::ConstTensorView(x.data(), Shape{2, 3, 4, 5}),
                                  nn::TensorView{y.data(), Shape{2, 1, 3, 5}}),
               nn::Error);
}

}  // namespace
