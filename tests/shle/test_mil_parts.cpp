// The parts of the OpenCV-exact MIL tracker that can be checked on their own:
// the C library's rand() re-created, the window sampler's counts and draws, and
// the Haar features' geometry.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <vector>

#include "shle/mil_boost.h"
#include "shle/mil_haar.h"
#include "shle/mil_random.h"
#include "shle/mil_sampler.h"
#include "shle/tracker.h"

namespace {

// glibc's own generator through its reentrant API (no process-global state).
std::vector<int> glibc_random_r(unsigned seed, int n) {
  static char state[128];
  random_data data{};
  EXPECT_EQ(initstate_r(seed, state, sizeof state, &data), 0);
  std::vector<int> out;
  for (int i = 0; i < n; ++i) {
    std::int32_t v = 0;
    random_r(&data, &v);
    out.push_back(v);
  }
  return out;
}

TEST(MilParts, GlibcRandIsTheCLibrarysSequence) {
  for (unsigned seed : {1u, 7u, 123456789u, 0u}) {
    const std::vector<int> want = glibc_random_r(seed, 5000);
    shle::GlibcRand r(seed);
    for (int i = 0; i < 5000; ++i) ASSERT_EQ(r.next(), want[i]) << "seed " << seed << " draw " << i;
  }
  // rand() with no srand() is seed 1: 1804289383 first, as every glibc program sees.
  EXPECT_EQ(shle::GlibcRand().next(), 1804289383);
}

TEST(MilParts, SamplerDrawsOncePerCandidateAndKeepsTheDisc) {
  // Interior: a 7x7 rectangle of candidates for radius 3, 25 inside the disc.
  shle::CvRng rng, mirror;
  std::vector<shle::MilWindow> w;
  shle::mil_sample(200, 300, 100, 80, 40, 30, 3.0f, 0.0f, 1000000, &rng, &w);
  EXPECT_EQ(w.size(), 25u);
  for (const shle::MilWindow& p : w) EXPECT_LT((p.x - 100) * (p.x - 100) + (p.y - 80) * (p.y - 80), 9);
  for (int i = 0; i < 49; ++i) mirror.next();
  EXPECT_EQ(rng.next(), mirror.next());
  // Clipped at the image's top-left and its last usable row/column (rows - h - 1).
  shle::CvRng r2;
  shle::mil_sample(50, 60, 1, 2, 20, 10, 25.0f, 0.0f, 1000000, &r2, &w);
  ASSERT_FALSE(w.empty());
  for (const shle::MilWindow& p : w) {
    EXPECT_GE(p.x, 0);
    EXPECT_GE(p.y, 0);
    EXPECT_LE(p.x, 60 - 20 - 1);
    EXPECT_LE(p.y, 50 - 10 - 1);
  }
  // Negatives: the annulus, at most maxnum.
  shle::CvRng r3;
  shle::mil_sample(400, 500, 200, 150, 40, 30, 50.0f, 4.5f, 65, &r3, &w);
  EXPECT_LE(w.size(), 65u);
  EXPECT_GT(w.size(), 30u);
  for (const shle::MilWindow& p : w) {
    const int d = (p.x - 200) * (p.x - 200) + (p.y - 150) * (p.y - 150);
    EXPECT_GE(d, 21);
    EXPECT_LT(d, 2500);
  }
  // No room for the window: nothing, no draw.
  shle::CvRng r4, untouched;
  shle::mil_sample(20, 20, 0, 0, 30, 10, 3.0f, 0.0f, 1000000, &r4, &w);
  EXPECT_TRUE(w.empty());
  EXPECT_EQ(r4.next(), untouched.next());
}

TEST(MilParts, HaarFeaturesLieInsideWithAreaAtLeastNine) {
  shle::GlibcRand r;
  int types[5] = {};
  for (int i = 0; i < 2000; ++i) {
    shle::HaarFeature f;
    ASSERT_TRUE(shle::draw_haar_feature(37, 23, &r, &f));
    ASSERT_GE(f.count, 2);
    ASSERT_LE(f.count, 4);
    ++types[f.count];
    for (int a = 0; a < f.count; ++a) {
      const shle::HaarFeature::Area& q = f.areas[a];
      EXPECT_GE(q.x, 0);
      EXPECT_GE(q.y, 0);
      EXPECT_LT(q.x + q.w, 37);
      EXPECT_LT(q.y + q.h, 23);
    }
  }
  EXPECT_GT(types[2], 0);
  EXPECT_GT(types[3], 0);
  EXPECT_GT(types[4], 0);
  // A patch too small for any feature fails at once instead of looping forever
  // (and leaves rand() untouched); a thin but feasible one succeeds.
  shle::HaarFeature f;
  shle::GlibcRand before = r;
  EXPECT_FALSE(shle::draw_haar_feature(2, 2, &r, &f));
  EXPECT_FALSE(shle::draw_haar_feature(300, 1, &r, &f));
  EXPECT_EQ(r.next(), before.next());
  EXPECT_TRUE(shle::draw_haar_feature(2, 11, &r, &f));
  EXPECT_TRUE(shle::draw_haar_feature(300, 3, &r, &f));
}

TEST(MilParts, HaarValueIsTheWeightedMeanDifference) {
  // Left half 10, right half 110: a side-by-side feature over the edge gives
  // mean(left) - mean(right) = -100 (float sums here are exact).
  std::vector<std::uint8_t> px(40 * 30);
  for (int y = 0; y < 30; ++y)
    for (int x = 0; x < 40; ++x) px[y * 40 + x] = x < 20 ? 10 : 110;
  shle::MilIntegral ii;
  shle::mil_integral(shle::GrayView{40, 30, px.data()}, 32, 3, &ii);
  shle::HaarFeature f;
  f.count = 2;
  f.areas[0] = {5, 4, 10, 8, 1.0f / 80};
  f.areas[1] = {15, 4, 10, 8, -1.0f / 80};
  EXPECT_FLOAT_EQ(shle::haar_value(f, ii, 5, 3, 30, 20), -100.0f);
  // Shifted left by 5: the right area is half 10, half 110 (mean 60).
  EXPECT_FLOAT_EQ(shle::haar_value(f, ii, 0, 3, 30, 20), -50.0f);
}

}  // namespace

namespace {

TEST(MilParts, ReadsTheBlueChannelOthersReadLuma) {
  shle::RgbImage rgb;
  rgb.width = 2;
  rgb.height = 1;
  rgb.rgb = {10, 20, 30, 200, 100, 50};
  shle::GrayImage g;
  shle::MilTracker().input_channel(rgb, &g);
  ASSERT_EQ(g.px.size(), 2u);
  EXPECT_EQ(g.px[0], 30);
  EXPECT_EQ(g.px[1], 50);
  shle::GrayImage luma = shle::to_gray(rgb);
  shle::NccTracker().input_channel(rgb, &g);
  EXPECT_EQ(g.px, luma.px);
}

}  // namespace

namespace {

TEST(MilParts, BadInputFailsCleanly) {
  std::vector<std::uint8_t> px(120 * 90);
  for (std::size_t i = 0; i < px.size(); ++i) px[i] = static_cast<std::uint8_t>((i * 37) ^ (i >> 5));
  const shle::GrayView img{120, 90, px.data()};
  shle::MilTracker t;
  shle::Box b{1, 2, 3, 4};
  EXPECT_FALSE(t.update(img, &b));                                  // not seeded
  EXPECT_FALSE(t.init(img, shle::Box{0, 0, 130, 40}));              // wider than the image
  EXPECT_FALSE(t.init(img, shle::Box{-30, 10, -5, 40}));            // left of the image
  EXPECT_FALSE(t.init(img, shle::Box{10, 10, 10.5, 40}));           // zero width after truncation
  EXPECT_FALSE(t.init(img, shle::Box{NAN, 10, 40, 40}));
  EXPECT_FALSE(t.init(shle::GrayView{120, 90, nullptr}, shle::Box{10, 10, 40, 40}));
  EXPECT_FALSE(t.init(shle::GrayView{70000, 1, px.data()}, shle::Box{10, 0, 40, 1}));  // row sums inexact
  ASSERT_TRUE(t.init(img, shle::Box{40, 30, 70, 55}));
  // A next frame too small for the window: no detection, box untouched.
  const shle::GrayView small{32, 20, px.data()};
  EXPECT_FALSE(t.update(small, &b));
  EXPECT_EQ(b.x0, 1);
  EXPECT_TRUE(t.update(img, &b));
  EXPECT_EQ(b.width(), 30);
  EXPECT_EQ(b.height(), 25);
}

}  // namespace
