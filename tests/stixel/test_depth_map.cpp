#include <gtest/gtest.h>

#include <cmath>

#include "stixel/depth_map.h"
#include "stixel/error.h"
#include "stixel/image_header.h"

namespace {

stixel::Stixel make(int u, int vT, int vB, float d, int width = 4) {
  stixel::Stixel s;
  s.u = u;
  s.vT = vT;
  s.vB = vB;
  s.d = d;
  s.width = width;
  return s;
}

}  // namespace

TEST(DepthMap, MinimumOverInclusiveRectangles) {
  stixel::StixelWorld w;
  w.context.calibration.width = 12;
  w.context.calibration.height = 10;
  w.stixels = {make(4, 2, 5, 10.0f), make(6, 4, 8, 7.0f), make(10, 9, 1, 3.0f),
               make(0, 0, 0, 1.0f) /* no height: skipped */, make(11, 3, 6, 2.0f) /* right clipped */};
  const stixel::DepthMap m = stixel::depth_map(w);
  ASSERT_EQ(m.width, 12);
  ASSERT_EQ(m.height, 10);
  auto at = [&](int x, int y) { return m.depth[y * 12 + x]; };
  EXPECT_EQ(at(2, 2), 10.0f);  // columns 4-2 .. 4+2, rows 2..5
  EXPECT_EQ(at(6, 5), 7.0f);   // overlap of the first two: the nearer wins
  EXPECT_EQ(at(2, 5), 10.0f);
  EXPECT_TRUE(std::isnan(at(1, 2)));
  EXPECT_TRUE(std::isnan(at(2, 6)));
  EXPECT_EQ(at(8, 1), 3.0f);   // vT > vB: rows 1..9
  EXPECT_EQ(at(9, 9), 3.0f);
  EXPECT_EQ(at(11, 4), 2.0f);  // columns 9..13 clipped at width - 1; 2 m < 3 m
  EXPECT_TRUE(std::isnan(at(0, 0)));
}

TEST(DepthMap, SizeFallsBackToImageHeaderThenExtents) {
  stixel::StixelWorld w;
  w.stixels = {make(10, 1, 6, 5.0f)};
  // PNG signature + IHDR of a 33 x 17 image.
  w.image = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A, 0, 0, 0, 13, 'I', 'H', 'D', 'R', 0, 0, 0, 33, 0, 0, 0, 17};
  stixel::DepthMap m = stixel::depth_map(w);
  EXPECT_EQ(m.width, 33);
  EXPECT_EQ(m.height, 17);
  // JPEG: SOI, an APP0 segment, then SOF0 with height 20, width 40.
  w.image = {0xFF, 0xD8, 0xFF, 0xE0, 0x00, 0x04, 0x00, 0x00, 0xFF, 0xC0, 0x00, 0x0B,
             0x08, 0x00, 20,   0x00, 40,   0x01, 0x01, 0x11, 0x00};
  m = stixel::depth_map(w);
  EXPECT_EQ(m.width, 40);
  EXPECT_EQ(m.height, 20);
  int iw = 0, ih = 0;
  EXPECT_FALSE(stixel::image_size(w.image.data(), 12, &iw, &ih));  // truncated before SOF
  // No image: u + max(1, w//2) + 1 by max(vB) + 1.
  w.image.clear();
  m = stixel::depth_map(w);
  EXPECT_EQ(m.width, 13);
  EXPECT_EQ(m.height, 7);
  // Explicit size wins.
  m = stixel::depth_map(w, 5, 4);
  EXPECT_EQ(m.width, 5);
  EXPECT_EQ(m.height, 4);
  EXPECT_THROW(stixel::depth_map(stixel::StixelWorld{}), stixel::Error);
}

TEST(DepthMap, PredictionRasterTakesTheMostProbableCandidate) {
  // [A=3, N=2, U=3], H = 64, v_scale 8 -> 8 rows.
  const int N = 2, U = 3;
  std::vector<float> p(3 * N * U, 0.0f);
  auto at = [&](int a, int n, int u) -> float& { return p[(a * N + n) * U + u]; };
  at(2, 0, 0) = 0.2f;
  at(2, 1, 0) = 0.7f;  // column 0: candidate 1
  at(1, 1, 0) = 0.25f;  // vT = round(16) = 16 -> row 2
  at(0, 1, 0) = 0.5f;   // vB = 32 -> row 4
  at(2, 0, 1) = 0.4f;   // column 1: tie at 0.4 -> first (candidate 0)
  at(2, 1, 1) = 0.4f;
  at(1, 0, 1) = 0.9f;  // inverted: vT 58 > vB 0 -> swapped
  at(0, 0, 1) = 0.0f;
  // column 2: all P = 0 -> candidate 0 with rows 0..0
  stixel::Anchors a = stixel::linear_anchors(10, 20, 2);
  stixel::DepthRaster r = stixel::prediction_depth_raster(p.data(), 3, N, U, a, 64, 8);
  ASSERT_EQ(r.rows, 8);
  ASSERT_EQ(r.columns, 3);
  auto d = [&](int row, int col) { return r.valid[row * 3 + col] ? r.depth[row * 3 + col] : -1.0f; };
  EXPECT_EQ(d(1, 0), -1.0f);
  EXPECT_EQ(d(2, 0), 20.0f);
  EXPECT_EQ(d(4, 0), 20.0f);
  EXPECT_EQ(d(5, 0), -1.0f);
  for (int row = 0; row <= 7; ++row) EXPECT_EQ(d(row, 1), 10.0f) << row;  // 0..58/8 = 7
  EXPECT_EQ(d(0, 2), 10.0f);
  EXPECT_EQ(d(1, 2), -1.0f);
  // A threshold drops columns whose best P is below it.
  r = stixel::prediction_depth_raster(p.data(), 3, N, U, a, 64, 8, 0.5);
  EXPECT_EQ(d(2, 0), 20.0f);
  EXPECT_EQ(d(0, 1), -1.0f);
  EXPECT_EQ(d(0, 2), -1.0f);
  // Round half to even in float32: 0.5 / 64 * 64 = 0.5 -> 0; 1.5 -> 2.
  std::fill(p.begin(), p.end(), 0.0f);
  at(2, 0, 0) = 1.0f;
  at(1, 0, 0) = 12.5f / 64;   // 12.5 -> 12 -> row 1
  at(0, 0, 0) = 15.5f / 64;   // 15.5 -> 16 -> row 2
  r = stixel::prediction_depth_raster(p.data(), 3, N, U, a, 64, 8);
  EXPECT_EQ(d(0, 0), -1.0f);
  EXPECT_EQ(d(1, 0), 10.0f);
  EXPECT_EQ(d(2, 0), 10.0f);
  EXPECT_EQ(d(3, 0), -1.0f);
}
