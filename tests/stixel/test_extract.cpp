#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "stixel/error.h"
#include "stixel/extract.h"

namespace {

// Prediction [A, N, U] filled with a constant, then individual cells set.
struct Pred {
  int A, N, U;
  std::vector<float> v;
  Pred(int a, int n, int u, float fill) : A(a), N(n), U(u), v(static_cast<std::size_t>(a) * n * u, fill) {}
  float& at(int a, int n, int u) { return v[(static_cast<std::size_t>(a) * N + n) * U + u]; }
};

stixel::Anchors small_anchors(int n) { return stixel::linear_anchors(5, 5 + (n - 1), n); }

}  // namespace

TEST(Extract, ThreeAttributesColumnMajorOrderAndFields) {
  Pred p(3, 4, 3, 0.0f);
  // (u=2, n=1) and (u=0, n=3) and (u=0, n=0) pass the threshold.
  p.at(2, 1, 2) = 0.9f;
  p.at(0, 1, 2) = 0.5f;   // vB
  p.at(1, 1, 2) = 0.25f;  // vT
  p.at(2, 3, 0) = 0.36f;
  p.at(2, 0, 0) = 1.0f;
  p.at(2, 2, 1) = 0.3599f;
  stixel::ExtractOptions o;
  o.threshold = 0.36;
  o.image_height = 1280;
  stixel::StixelWorld w = stixel::extract(p.v.data(), 3, 4, 3, small_anchors(4), o);
  ASSERT_EQ(w.stixels.size(), 3u);  // 0.36f = 0.36000001430511475 >= 0.36; 0.3599f is not
  EXPECT_EQ(w.stixels[0].u, 0);
  EXPECT_EQ(w.stixels[0].d, 5.0f);  // n = 0
  EXPECT_EQ(w.stixels[0].vT, 1);    // int(0 * H + 1)
  EXPECT_EQ(w.stixels[1].u, 0);
  EXPECT_EQ(w.stixels[1].d, 8.0f);  // n = 3 comes after n = 0 in column 0
  EXPECT_EQ(w.stixels[2].u, 16);    // column 2 * 8
  EXPECT_EQ(w.stixels[2].vB, 641);  // int(0.5 * 1280 + 1)
  EXPECT_EQ(w.stixels[2].vT, 321);
  EXPECT_EQ(w.stixels[2].d, 6.0f);
  EXPECT_EQ(w.stixels[2].confidence, 0.9f);
  EXPECT_EQ(w.stixels[2].width, 8);
  EXPECT_EQ(w.stixels[2].label, 0);
  EXPECT_EQ(w.stixels[2].cluster, 0);
  // The comparison is in double, as numpy compares a float32 scalar with a Python
  // float: this threshold rounds to 0.36f in float but lies above it.
  o.threshold = 0.3600000143051148;
  ASSERT_EQ(static_cast<float>(o.threshold), 0.36f);
  w = stixel::extract(p.v.data(), 3, 4, 3, small_anchors(4), o);
  ASSERT_EQ(w.stixels.size(), 2u);
  EXPECT_EQ(w.stixels[1].u, 16);
}

TEST(Extract, ThresholdZeroKeepsEverythingButNaN) {
  Pred p(4, 64, 240, 0.5f);
  p.at(3, 10, 100) = NAN;
  stixel::ExtractOptions o;
  o.threshold = 0.0;
  const stixel::StixelWorld w = stixel::extract(p.v.data(), 4, 64, 240, stixel::tangent_anchors(), o);
  EXPECT_EQ(w.stixels.size(), 240u * 64 - 1);
  EXPECT_EQ(w.stixels.back().u, 239 * 8);
}

TEST(Extract, RowsAreExactTruncations) {
  Pred p(3, 1, 4, 1.0f);
  const int H = 1280;
  // v_hat * H + 1 computed exactly: 0.1f * 1280 = 128.00000190734863 -> 129;
  // in float32 arithmetic it would round to 128.0 as well, but nextafter below
  // 0.1f gives 127.99999... -> 128.
  p.at(1, 0, 0) = 0.1f;
  p.at(1, 0, 1) = std::nextafter(0.1f, 0.0f);
  p.at(1, 0, 2) = 1.0f;  // saturated sigmoid: row H + 1, as the reference
  p.at(1, 0, 3) = 0.0f;
  stixel::ExtractOptions o;
  o.threshold = 0.5;
  o.image_height = H;
  stixel::Anchors one;
  one.depth = {7.0f};
  const stixel::StixelWorld w = stixel::extract(p.v.data(), 3, 1, 4, one, o);
  ASSERT_EQ(w.stixels.size(), 4u);
  EXPECT_EQ(w.stixels[0].vT, 129);
  // Exact arithmetic gives 128.99999237... -> 128; float32 arithmetic would
  // round the sum to 129.0 (a tie, to even).
  EXPECT_EQ(w.stixels[1].vT, 128);
  EXPECT_EQ(w.stixels[2].vT, H + 1);
  EXPECT_EQ(w.stixels[3].vT, 1);
  EXPECT_EQ(w.stixels[2].vB, H + 1);
  EXPECT_EQ(w.stixels[0].d, 7.0f);
}

TEST(Extract, FourAttributesDecodeResidualDepth) {
  Pred p(4, 2, 1, 0.0f);
  p.at(3, 0, 0) = 0.8f;
  p.at(3, 1, 0) = 0.8f;
  p.at(2, 0, 0) = 0.1f;
  p.at(2, 1, 0) = 0.0f;
  const stixel::Anchors a = stixel::linear_anchors(10, 20, 2);
  stixel::ExtractOptions o;
  o.threshold = 0.5;
  stixel::StixelWorld w = stixel::extract(p.v.data(), 4, 2, 1, a, o);
  ASSERT_EQ(w.stixels.size(), 2u);
  // The authors' decoding: exp(log(anchor) + d_res) in double.
  EXPECT_EQ(w.stixels[0].d, static_cast<float>(std::exp(std::log(10.0) + static_cast<double>(0.1f))));
  EXPECT_EQ(stixel::decode_depth_residual(10.0, 0.1f), std::exp(std::log(10.0) + static_cast<double>(0.1f)));
  EXPECT_EQ(w.stixels[1].d, 20.0f);
  EXPECT_EQ(w.stixels[0].confidence, 0.8f);
  // Focal adaptation scales every depth.
  o.depth_scale = 0.5;
  w = stixel::extract(p.v.data(), 4, 2, 1, a, o);
  EXPECT_EQ(w.stixels[1].d, 10.0f);
  // A huge negative residual gives 0 as in the reference, whose eps guards the
  // anchor (log of it), not the result.
  p.at(2, 0, 0) = -1e4f;
  o.depth_scale = 1.0;
  w = stixel::extract(p.v.data(), 4, 2, 1, a, o);
  EXPECT_EQ(w.stixels[0].d, 0.0f);
  EXPECT_DOUBLE_EQ(stixel::decode_depth_residual(0.0, 0.0f), 1e-6);
}

TEST(Extract, CustomWidthAndHeight) {
  Pred p(3, 1, 3, 0.75f);
  stixel::ExtractOptions o;
  o.threshold = 0.5;
  o.image_height = 1200;
  o.stixel_width = 16;
  stixel::Anchors one;
  one.depth = {12.5f};
  const stixel::StixelWorld w = stixel::extract(p.v.data(), 3, 1, 3, one, o);
  ASSERT_EQ(w.stixels.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(w.stixels[i].u, 16 * i);
    EXPECT_EQ(w.stixels[i].width, 16);
    EXPECT_EQ(w.stixels[i].vB, 901);  // int(0.75 * 1200 + 1)
    EXPECT_EQ(w.stixels[i].d, 12.5f);
  }
}

TEST(Extract, InvalidInputsAreErrors) {
  Pred p(3, 4, 2, 0.9f);
  const stixel::Anchors a4 = small_anchors(4);
  stixel::ExtractOptions o;
  EXPECT_THROW(stixel::extract(p.v.data(), 5, 4, 2, a4, o), stixel::Error);
  EXPECT_THROW(stixel::extract(p.v.data(), 3, 0, 2, a4, o), stixel::Error);
  EXPECT_THROW(stixel::extract(p.v.data(), 3, 4, 2, small_anchors(3), o), stixel::Error);
  EXPECT_THROW(stixel::extract(nullptr, 3, 4, 2, a4, o), stixel::Error);
  for (double t : {-0.1, 1.5, static_cast<double>(NAN)}) {
    o.threshold = t;
    try {
      stixel::extract(p.v.data(), 3, 4, 2, a4, o);
      ADD_FAILURE() << "threshold " << t << " accepted";
    } catch (const stixel::Error& e) {
      EXPECT_NE(std::string(e.what()).find("threshold must be in [0, 1]"), std::string::npos);
    }
  }
  o = stixel::ExtractOptions();
  o.image_height = 0;
  EXPECT_THROW(stixel::extract(p.v.data(), 3, 4, 2, a4, o), stixel::Error);
  o = stixel::ExtractOptions();
  o.depth_scale = 0;
  EXPECT_THROW(stixel::extract(p.v.data(), 3, 4, 2, a4, o), stixel::Error);
  o = stixel::ExtractOptions();
  p.at(1, 2, 1) = NAN;  // vT of a kept candidate
  try {
    stixel::extract(p.v.data(), 3, 4, 2, a4, o);
    ADD_FAILURE() << "NaN vT accepted";
  } catch (const stixel::Error& e) {
    EXPECT_NE(std::string(e.what()).find("vT of candidate 2, column 1"), std::string::npos) << e.what();
  }
  p.at(1, 2, 1) = 1e30f;  // not a sigmoid output: row out of int range
  EXPECT_THROW(stixel::extract(p.v.data(), 3, 4, 2, a4, o), stixel::Error);
  Pred q(4, 4, 2, 0.9f);
  q.at(2, 0, 0) = INFINITY;
  EXPECT_THROW(stixel::extract(q.v.data(), 4, 4, 2, a4, o), stixel::Error);
}
