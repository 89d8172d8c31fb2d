// Stage 2 on hand-made disparity maps with known answers.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "shle/height.h"

namespace {

// 64x48 map, f = 100, principal point (32, 24), bf = 10: disparity 1 -> 10 m,
// and H = 1.45 - (v - 24) * Z / 100.
shle::Calibration small_calib() {
  shle::Calibration c;
  c.intrinsics = geometry::Intrinsics{100, 100, 32, 24};
  c.bf = 10;
  c.mount_height = 1.45;
  c.width = 64;
  c.height = 48;
  return c;
}

shle::DisparityMap blank(float value = 0) {
  shle::DisparityMap m;
  m.width = 64;
  m.height = 48;
  m.d.assign(64 * 48, value);
  return m;
}

void fill(shle::DisparityMap& m, int u0, int u1, int v0, int v1, float d) {
  for (int v = v0; v < v1; ++v)
    for (int u = u0; u < u1; ++u) m.d[v * m.width + u] = d;
}

TEST(Height, ExtensionClippingAndPixelRanges) {
  shle::HeightEstimator est(small_calib(), {});
  shle::DisparityMap m = blank(1.0f);
  shle::HeightResult r = est.estimate(m, shle::Box{10.7, 5.9, 20.2, 8.1});
  EXPECT_EQ(r.window.x0, 10.7);
  EXPECT_EQ(r.window.y0, 0.0);    // 5.9 - 20 clipped
  EXPECT_EQ(r.window.y1, 28.1);   // 8.1 + 20
  EXPECT_EQ(r.u0, 10);
  EXPECT_EQ(r.u1, 20);            // int(20.2) exclusive
  EXPECT_EQ(r.v0, 0);
  EXPECT_EQ(r.v1, 28);            // int(28.1) exclusive
  EXPECT_EQ(r.valid, 10u * 28u);
  shle::HeightOptions no_ext;
  no_ext.extend_top = no_ext.extend_bottom = 0;
  shle::HeightEstimator est0(small_calib(), no_ext);
  r = est0.estimate(m, shle::Box{-5, 40.5, 70, 60});
  EXPECT_EQ(r.window.x0, 0.0);
  EXPECT_EQ(r.window.x1, 64.0);
  EXPECT_EQ(r.window.y1, 48.0);
  EXPECT_EQ(r.v0, 40);
  EXPECT_EQ(r.v1, 48);
}

TEST(Height, BarHeightIsMeanOfLowestPoints) {
  shle::DisparityMap m = blank();
  fill(m, 10, 30, 5, 8, 1.0f);  // a bar at 10 m on rows 5..7
  shle::HeightEstimator est(small_calib(), {});
  shle::HeightResult r = est.estimate(m, shle::Box{10, 5, 30, 8});
  ASSERT_TRUE(r.has_height) << r.problem;
  EXPECT_EQ(r.points, 60u);
  EXPECT_EQ(r.window_points, 60u);
  EXPECT_EQ(r.centre_depth, 10.0);
  // The 10 lowest points are on row 7: H = 1.45 + (24 - 7) * 10 / 100 = 3.15.
  EXPECT_NEAR(r.height, 3.15, 1e-12);
  // N = 30 takes row 7 (20 points) and 10 points of row 6 (H = 3.25).
  shle::HeightOptions o;
  o.lowest_n = 30;
  shle::HeightEstimator est30(small_calib(), o);
  EXPECT_NEAR(est30.estimate(m, shle::Box{10, 5, 30, 8}).height, (20 * 3.15 + 10 * 3.25) / 30, 1e-12);
  // Fewer points than N: all of them.
  o.lowest_n = 1000;
  shle::HeightEstimator all(small_calib(), o);
  EXPECT_NEAR(all.estimate(m, shle::Box{10, 5, 30, 8}).height, 3.25, 1e-12);
}

TEST(Height, DepthWindowRemovesBackgroundAndPrefilterRemovesLowPoints) {
  shle::DisparityMap m = blank();
  fill(m, 10, 30, 5, 8, 1.0f);      // bar, 10 m
  fill(m, 10, 30, 8, 10, 0.25f);    // background below the bar, 40 m, H 7.85 and 7.45
  fill(m, 10, 30, 22, 27, 1.0f);    // low stuff at 10 m: H = 1.65 .. 1.25 (rows 22, 23 pass)
  shle::HeightEstimator est(small_calib(), {});
  shle::HeightResult r = est.estimate(m, shle::Box{10, 5, 30, 8});
  ASSERT_TRUE(r.has_height);
  // Rows 22 (H 1.65) and 23 (H 1.55) pass the 1.5 m prefilter; rows 24.. do not.
  EXPECT_EQ(r.points, 60u + 40u + 40u);
  EXPECT_EQ(r.centre_depth, 10.0);
  EXPECT_EQ(r.window_points, 100u);
  EXPECT_NEAR(r.height, 1.55, 1e-12);  // the low 10 m points are the lowest in the window
  shle::HeightOptions o;
  o.min_height = 2.0;
  shle::HeightEstimator strict(small_calib(), o);
  EXPECT_NEAR(strict.estimate(m, shle::Box{10, 5, 30, 8}).height, 3.15, 1e-12);
  o.use_depth_window = false;
  shle::HeightEstimator nowin(small_calib(), o);
  // Without the window the background (H >= 7.45) is higher than the bar: the
  // bar's row 7 stays lowest.
  shle::HeightResult nw = nowin.estimate(m, shle::Box{10, 5, 30, 8});
  EXPECT_EQ(nw.window_points, 100u);
  EXPECT_NEAR(nw.height, 3.15, 1e-12);
}

TEST(Height, KdePicksTheDenserDepthAndNoKdeUsesTheMean) {
  shle::DisparityMap m = blank();
  fill(m, 0, 64, 0, 3, 0.5f);  // 192 points at 20 m, H 6.25 .. 5.85
  fill(m, 0, 10, 3, 5, 1.0f);  // 20 points at 10 m
  shle::HeightEstimator est(small_calib(), {});
  shle::HeightResult r = est.estimate(m, shle::Box{0, 0, 64, 5});
  EXPECT_EQ(r.centre_depth, 20.0);
  EXPECT_NEAR(r.height, 1.45 + (24 - 2) * 20.0 / 100, 1e-12);
  shle::HeightOptions o;
  o.use_kde = false;
  shle::HeightEstimator mean(small_calib(), o);
  shle::HeightResult rm = mean.estimate(m, shle::Box{0, 0, 64, 5});
  EXPECT_NEAR(rm.centre_depth, (192 * 20.0 + 20 * 10.0) / 212, 1e-12);
  // The mean (19.06 m) keeps neither cluster: no height.
  EXPECT_FALSE(rm.has_height);
  EXPECT_NE(rm.problem.find("no point in the depth window"), std::string::npos);
}

TEST(Height, EmptyWindowAroundIntegerMode) {
  // One point at 10.3 m and one at 11.7 m: the mode is 11 (2 k(0.7) > k(0.3) + k(1.7))
  // and the open window (10.4, 11.6) holds neither.
  shle::DisparityMap m = blank();
  m.d[2 * 64 + 5] = static_cast<float>(10.0 / 10.3);
  m.d[2 * 64 + 6] = static_cast<float>(10.0 / 11.7);
  shle::HeightEstimator est(small_calib(), {});
  shle::HeightResult r = est.estimate(m, shle::Box{0, 0, 64, 5});
  EXPECT_EQ(r.points, 2u);
  EXPECT_EQ(r.centre_depth, 11.0);
  EXPECT_FALSE(r.has_height);
  EXPECT_EQ(r.window_points, 0u);
}

TEST(Height, NoHeightCases) {
  shle::HeightEstimator est(small_calib(), {});
  shle::HeightResult r = est.estimate(blank(), shle::Box{10, 5, 30, 8});
  EXPECT_FALSE(r.has_height);
  EXPECT_EQ(r.valid, 0u);
  EXPECT_EQ(r.problem, "no valid disparity in the box");
  r = est.estimate(blank(1.0f), shle::Box{100, 5, 130, 8});
  EXPECT_FALSE(r.has_height);
  EXPECT_EQ(r.problem, "box lies outside the 64x48 disparity map");
  r = est.estimate(blank(1.0f), shle::Box{-50, -80, -10, -40});
  EXPECT_EQ(r.problem, "box lies outside the 64x48 disparity map");
  r = est.estimate(blank(1.0f), shle::Box{10, NAN, 30, 8});
  EXPECT_EQ(r.problem, "box has non-finite coordinates");
  r = est.estimate(blank(1.0f), shle::Box{10, 5, 30, INFINITY});
  EXPECT_EQ(r.problem, "box has non-finite coordinates");
  shle::DisparityMap low = blank();
  fill(low, 0, 64, 30, 48, 1.0f);  // only points below the prefilter
  r = est.estimate(low, shle::Box{0, 30, 64, 48});
  EXPECT_FALSE(r.has_height);
  EXPECT_GT(r.valid, 0u);
  EXPECT_NE(r.problem.find("height prefilter"), std::string::npos);
}

// Zero-sized boxes (a boxes CSV accepts x1 == x0, y1 == y0): no crash, a plain
// reason; a zero height still reads the extension rows as the released code does.
TEST(Height, ZeroSizedBoxes) {
  shle::DisparityMap m = blank();
  fill(m, 0, 64, 0, 20, 2.0f);
  shle::HeightEstimator est(small_calib(), {});
  shle::HeightResult r = est.estimate(m, shle::Box{10, 5, 10, 15});
  EXPECT_FALSE(r.has_height);
  EXPECT_EQ(r.problem, "box is empty (zero width, or zero height without extension)");
  r = est.estimate(m, shle::Box{30, 5, 10, 15});  // inverted
  EXPECT_EQ(r.problem, "box is empty (zero width, or zero height without extension)");
  r = est.estimate(m, shle::Box{10, 10, 30, 10});  // zero height, 20 + 20 px extension
  EXPECT_EQ(r.v0, 0);
  EXPECT_EQ(r.v1, 30);
  EXPECT_GT(r.valid, 0u);
  shle::HeightOptions no_ext;
  no_ext.extend_top = no_ext.extend_bottom = 0;
  shle::HeightEstimator tight(small_calib(), no_ext);
  r = tight.estimate(m, shle::Box{10, 10, 30, 10});
  EXPECT_FALSE(r.has_height);
  EXPECT_EQ(r.problem, "box is empty (zero width, or zero height without extension)");
}

TEST(Height, InvalidDisparitiesAreSkipped) {
  shle::DisparityMap m = blank();
  fill(m, 10, 30, 5, 8, 1.0f);
  const float bad[] = {-1.0f, std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                       1e-30f, 0.0f};
  int k = 0;
  for (float b : bad) m.d[8 * 64 + 10 + k++] = b;  // row 8, below the bar
  shle::HeightEstimator est(small_calib(), {});
  shle::HeightResult r = est.estimate(m, shle::Box{10, 5, 30, 9});
  EXPECT_EQ(r.valid, 60u);
  EXPECT_NEAR(r.height, 3.15, 1e-12);
}

TEST(Height, AbsoluteValueOfMeanY) {
  // Prefilter disabled and only points below the road: the released abs(mean(Y)).
  shle::DisparityMap m = blank();
  fill(m, 0, 64, 40, 41, 0.25f);  // 40 m, Y = 16 * 40 / 100 - 1.45 = 4.95 (below ground)
  shle::HeightOptions o;
  o.min_height = -1e9;
  shle::HeightEstimator est(small_calib(), o);
  shle::HeightResult r = est.estimate(m, shle::Box{0, 40, 64, 41});
  ASSERT_TRUE(r.has_height);
  EXPECT_NEAR(r.height, 4.95, 1e-12);
}

TEST(Height, LevelExtrinsicsEqualLevelFormula) {
  shle::DisparityMap m = blank();
  fill(m, 10, 30, 5, 8, 1.0f);
  fill(m, 5, 60, 8, 20, 0.3f);
  shle::Calibration c = small_calib();
  shle::Calibration e = c;
  e.has_extrinsics = true;
  e.extrinsics = geometry::Extrinsics::level(1.45);
  shle::HeightEstimator a(c, {}), b(e, {});
  shle::HeightResult ra = a.estimate(m, shle::Box{5, 5, 60, 9}), rb = b.estimate(m, shle::Box{5, 5, 60, 9});
  EXPECT_EQ(ra.points, rb.points);
  EXPECT_EQ(ra.centre_depth, rb.centre_depth);
  EXPECT_NEAR(ra.height, rb.height, 1e-12);
  // A camera pitched down sees each pixel's point lower than the level formula
  // assumes.
  shle::Calibration p = c;
  p.has_extrinsics = true;
  p.extrinsics = geometry::Extrinsics::pitched(0.01, 1.45);
  shle::HeightEstimator pe(p, {});
  EXPECT_LT(pe.estimate(m, shle::Box{10, 5, 30, 8}).height, ra.height);
}

TEST(Height, RepeatableAndReusable) {
  shle::DisparityMap m = blank();
  for (int i = 0; i < 64 * 48; ++i) m.d[i] = static_cast<float>(0.2 + 0.01 * ((i * 7919) % 97));
  shle::HeightEstimator est(small_calib(), {});
  shle::HeightResult a = est.estimate(m, shle::Box{0, 0, 64, 20});
  shle::HeightResult b = est.estimate(m, shle::Box{3, 2, 30, 9});
  shle::HeightResult c = est.estimate(m, shle::Box{0, 0, 64, 20});
  ASSERT_TRUE(a.has_height);
  EXPECT_EQ(a.height, c.height);
  EXPECT_EQ(a.points, c.points);
  shle::HeightEstimator fresh(small_calib(), {});
  EXPECT_EQ(fresh.estimate(m, shle::Box{3, 2, 30, 9}).height, b.height);
}

TEST(Height, OptionsAreValidated) {
  shle::HeightOptions o;
  o.lowest_n = 0;
  EXPECT_ANY_THROW(shle::HeightEstimator(small_calib(), o));
  o = {};
  o.sigma = 0;
  EXPECT_ANY_THROW(shle::HeightEstimator(small_calib(), o));
  o = {};
  o.extend_top = -1;
  EXPECT_ANY_THROW(shle::HeightEstimator(small_calib(), o));
  o = {};
  o.grid_step = NAN;
  EXPECT_ANY_THROW(shle::HeightEstimator(small_calib(), o));
}

}  // namespace
