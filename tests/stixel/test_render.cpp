// Pictures: colours at known pixels, draw order, compositing.
#include <gtest/gtest.h>

#include "stixel/colormap.h"
#include "stixel/error.h"
#include "stixel/render.h"

namespace {

using stixel::Rgb;

stixel::Stixel make(int u, int vT, int vB, float d, float conf = 0.9f, int width = 8) {
  stixel::Stixel s;
  s.u = u;
  s.vT = vT;
  s.vB = vB;
  s.d = d;
  s.width = width;
  s.confidence = conf;
  return s;
}

stixel::RgbImage solid(int w, int h, Rgb c) {
  stixel::RgbImage img;
  img.width = w;
  img.height = h;
  img.pixels.resize(static_cast<std::size_t>(w) * h * 3);
  for (std::size_t i = 0; i < img.pixels.size(); i += 3)
    for (int k = 0; k < 3; ++k) img.pixels[i + k] = c[k];
  return img;
}

Rgb pixel(const stixel::RgbImage& img, int x, int y) {
  const std::uint8_t* p = &img.pixels[(static_cast<std::size_t>(y) * img.width + x) * 3];
  return {p[0], p[1], p[2]};
}

}  // namespace

TEST(Colormap, MatplotlibRdYlGnAndJet) {
  // Values of matplotlib's cm.RdYlGn / cm.jet converted with int(c * 255).
  EXPECT_EQ(stixel::rdylgn(0.0), (Rgb{165, 0, 38}));
  EXPECT_EQ(stixel::rdylgn(0.5), (Rgb{254, 254, 189}));
  EXPECT_EQ(stixel::rdylgn(1.0), (Rgb{0, 104, 55}));
  EXPECT_EQ(stixel::rdylgn(-3.0), (Rgb{165, 0, 38}));  // under -> first colour
  EXPECT_EQ(stixel::rdylgn(7.0), (Rgb{0, 104, 55}));   // over -> last colour
  EXPECT_EQ(stixel::depth_color(20.0f), (Rgb{253, 190, 110}));
  EXPECT_EQ(stixel::depth_color(10.0f), (Rgb{217, 53, 41}));
  EXPECT_EQ(stixel::jet(0.0), (Rgb{0, 0, 127}));
  EXPECT_EQ(stixel::jet(1.0), (Rgb{127, 0, 0}));
  EXPECT_EQ(stixel::jet(0.5), (Rgb{124, 255, 121}));
  EXPECT_EQ(stixel::cluster_color(2, 4), stixel::jet(0.5));
}

TEST(Overlay, FarToNearWithPilCompositing) {
  const stixel::RgbImage bg = solid(40, 30, {0, 0, 0});
  stixel::StixelWorld w;
  // A near stixel listed first and a far one overlapping it: the near one must
  // end up on top. Width 8: columns u-4 .. u+4 (9 pixels, inclusive).
  w.stixels = {make(10, 5, 20, 5.0f), make(14, 0, 25, 50.0f), make(30, 10, 10, 5.0f) /* no height */,
               make(30, 2, 8, 5.0f, 0.4f) /* below min_confidence */};
  const stixel::RgbImage out = stixel::render_overlay(w, bg);
  // Alpha int(0.5 * 255) = 127 over black: PIL gives (82, 0, 19) for the 5 m
  // colour (165, 0, 38) and (0, 52, 27) for the 50 m colour (0, 104, 55).
  EXPECT_EQ(pixel(out, 10, 10), (Rgb{82, 0, 19}));
  EXPECT_EQ(pixel(out, 14, 10), (Rgb{82, 0, 19}));  // overlap: near on top
  EXPECT_EQ(pixel(out, 15, 10), (Rgb{0, 52, 27}));
  EXPECT_EQ(pixel(out, 14, 2), (Rgb{0, 52, 27}));
  EXPECT_EQ(pixel(out, 6, 5), (Rgb{82, 0, 19}));    // u - 4, vT: inclusive
  EXPECT_EQ(pixel(out, 5, 5), (Rgb{0, 0, 0}));
  EXPECT_EQ(pixel(out, 6, 21), (Rgb{0, 0, 0}));     // vB + 1
  EXPECT_EQ(pixel(out, 18, 25), (Rgb{0, 52, 27}));
  EXPECT_EQ(pixel(out, 19, 25), (Rgb{0, 0, 0}));
  EXPECT_EQ(pixel(out, 30, 5), (Rgb{0, 0, 0}));     // confidence 0.4 < 0.5
  // White background: 255 * (1 - 127/255) + c * 127/255, rounded.
  const stixel::RgbImage white = stixel::render_overlay(w, solid(40, 30, {255, 255, 255}));
  EXPECT_EQ(pixel(white, 10, 10), (Rgb{210, 128, 147}));
  // Lower the confidence bar: the fourth stixel appears.
  stixel::OverlayOptions o;
  o.min_confidence = 0.3;
  o.alpha = 1.0;
  const stixel::RgbImage opaque = stixel::render_overlay(w, bg, o);
  EXPECT_EQ(pixel(opaque, 30, 5), (Rgb{165, 0, 38}));
  EXPECT_EQ(pixel(opaque, 30, 8), (Rgb{165, 0, 38}));
  EXPECT_EQ(pixel(opaque, 30, 9), (Rgb{0, 0, 0}));  // the zero-height stixel stays invisible
}

TEST(Overlay, ClusterColoursAndErrors) {
  stixel::StixelWorld w;
  w.stixels = {make(5, 0, 9, 10.0f), make(20, 0, 9, 10.0f)};
  w.stixels[0].cluster = 0;
  w.stixels[1].cluster = 2;
  w.context.clusters = 2;
  stixel::OverlayOptions o;
  o.alpha = 1.0;
  o.color_by_cluster = true;
  const stixel::RgbImage out = stixel::render_overlay(w, solid(30, 10, {9, 9, 9}), o);
  EXPECT_EQ(pixel(out, 5, 5), stixel::jet(0.0));
  EXPECT_EQ(pixel(out, 20, 5), stixel::jet(1.0));
  stixel::RgbImage bad = solid(30, 10, {0, 0, 0});
  bad.pixels.pop_back();
  EXPECT_THROW(stixel::render_overlay(w, bad), stixel::Error);
  o.alpha = 1.5;
  EXPECT_THROW(stixel::render_overlay(w, solid(30, 10, {0, 0, 0}), o), stixel::Error);
}

TEST(Bev, StixelsLandWhereTheGeometrySaysAndColouredByMode) {
  const std::vector<float> K = {1000.0f, 0.0f, 500.0f, 0.0f, 1000.0f, 300.0f, 0.0f, 0.0f, 1.0f};
  const stixel::Projection p(K, {});
  stixel::StixelWorld w;
  // Straight ahead at 20 m, and 10 m to the right at 35 m (x = 300 * 35 / 1000 = 10.5 m).
  w.stixels = {make(500, 100, 300, 20.0f), make(800, 100, 300, 35.0f)};
  stixel::BevOptions o;
  o.grid = false;
  const stixel::RgbImage img = stixel::render_bev(w, p, o);
  ASSERT_EQ(img.width, 1024);
  // Canvas: x = (lateral + 35) * 1024 / 70, y = (70 - forward) * 1024 / 70.
  EXPECT_EQ(pixel(img, 512, 731), stixel::depth_color(20.0f));
  EXPECT_EQ(pixel(img, 665, 512), stixel::depth_color(35.0f));
  EXPECT_EQ(pixel(img, 512, 740), (Rgb{20, 20, 20}));
  EXPECT_EQ(pixel(img, 100, 100), (Rgb{20, 20, 20}));

  w.stixels[0].cluster = -1;
  w.stixels[1].cluster = 0;
  w.context.clusters = 0;
  o.color = stixel::BevOptions::Color::Cluster;
  o.grid = true;
  const stixel::RgbImage clusters = stixel::render_bev(w, p, o);
  EXPECT_EQ(pixel(clusters, 512, 731), (Rgb{110, 110, 110}));  // noise
  EXPECT_EQ(pixel(clusters, 665, 512), stixel::jet(0.0));
  // The forward axis runs up column 512; the 30 m ring crosses it at
  // y = 40 * 1024 / 70 = 585.1 (rings are drawn over the axes).
  EXPECT_EQ(pixel(clusters, 512, 100), (Rgb{90, 90, 90}));
  EXPECT_EQ(pixel(clusters, 512, 585), (Rgb{60, 60, 60}));
  EXPECT_EQ(pixel(clusters, 20, 20), (Rgb{20, 20, 20}));

  o.color = stixel::BevOptions::Color::Confidence;
  w.stixels[0].confidence = 1.0f;
  const stixel::RgbImage conf = stixel::render_bev(w, p, o);
  EXPECT_EQ(pixel(conf, 512, 731), (Rgb{0, 255, 0}));

  // Vehicle frame convention: lateral = y (left positive, drawn on the left).
  stixel::BevOptions v;
  v.lateral_axis = 1;
  v.forward_axis = 0;
  v.flip_lateral = true;
  EXPECT_NO_THROW(stixel::render_bev(w, p, v));
  v.forward_axis = 1;
  EXPECT_THROW(stixel::render_bev(w, p, v), stixel::Error);
  stixel::BevOptions tiny;
  tiny.width = 0;
  EXPECT_THROW(stixel::render_bev(w, p, tiny), stixel::Error);
}
