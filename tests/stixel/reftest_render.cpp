// Overlays against Pillow drawing the way pyStixel-lib does
// (tests/reference/stixel_render_ref.py): pixel for pixel.
#include "stixel/render.h"
#include "tests/stixel/reftest_util.h"

namespace {

void check(const std::string& tensor, const stixel::OverlayOptions& o) {
  const auto st = stxref::load("stixel_render.safetensors");
  const auto& shape = st.info("background").shape;
  stixel::RgbImage bg;
  bg.height = static_cast<int>(shape[0]);
  bg.width = static_cast<int>(shape[1]);
  bg.pixels = stxref::u8(st, "background");
  stixel::StixelWorld w;
  w.stixels = stxref::stixels(st);
  w.context.clusters = std::stoi(stxref::meta(st, "clusters"));
  const stixel::RgbImage out = stixel::render_overlay(w, bg, o);
  const std::vector<std::uint8_t> ref = stxref::u8(st, tensor);
  ASSERT_EQ(out.pixels.size(), ref.size());
  int mismatches = 0, changed = 0;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    changed += ref[i] != bg.pixels[i];
    if (out.pixels[i] != ref[i] && mismatches++ < 5)
      ADD_FAILURE() << tensor << ": pixel " << i / 3 % bg.width << "," << i / 3 / bg.width << " channel "
                    << i % 3 << ": ours " << int(out.pixels[i]) << ", Pillow " << int(ref[i]);
  }
  EXPECT_EQ(mismatches, 0);
  EXPECT_GT(changed, 10000);  // the picture really has stixels on it
}

}  // namespace

TEST(RenderRef, DepthOverlayMatchesPillow) {
  stixel::OverlayOptions o;
  o.alpha = 0.5;
  o.min_confidence = 0.5;
  check("overlay_depth", o);
}

TEST(RenderRef, ClusterOverlayMatchesPillow) {
  stixel::OverlayOptions o;
  o.alpha = 0.7;
  o.min_confidence = 0.2;
  o.color_by_cluster = true;
  check("overlay_clusters", o);
}

// pyStixel-lib's draw_stixels_birds_eye_view drawn with Pillow (window fitted to the
// data, 2-px lines at alpha 0.9, 3x3 ellipse dots): render_bev_fitted, pixel for pixel.
namespace {

void check_bev(const std::string& tensor, int width, int height, double prob, stixel::BevOptions::Color color) {
  const auto st = stxref::load("stixel_bev_fitted.safetensors");
  stixel::StixelWorld w;
  w.stixels = stxref::stixels(st);
  const stixel::Projection proj(st.f32("K"), {});
  stixel::BevOptions o;
  o.width = width;
  o.height = height;
  o.min_confidence = prob;
  o.color = color;
  const stixel::RgbImage out = stixel::render_bev_fitted(w, proj, o);
  const std::vector<std::uint8_t> ref = stxref::u8(st, tensor);
  ASSERT_EQ(out.pixels.size(), ref.size());
  int mismatches = 0, drawn = 0;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    drawn += ref[i] != 20;
    if (out.pixels[i] != ref[i] && mismatches++ < 5)
      ADD_FAILURE() << tensor << ": pixel " << i / 3 % width << "," << i / 3 / width << " channel " << i % 3
                    << ": ours " << int(out.pixels[i]) << ", Pillow " << int(ref[i]);
  }
  EXPECT_EQ(mismatches, 0);
  EXPECT_GT(drawn, 1500);  // the picture really has stixels on it
}

}  // namespace

TEST(RenderRef, FittedBevByDepthMatchesPillow) {
  check_bev("bev_depth", 300, 260, 0.5, stixel::BevOptions::Color::Depth);
}
TEST(RenderRef, FittedBevByClusterMatchesPillow) {
  check_bev("bev_cluster", 300, 260, 0.2, stixel::BevOptions::Color::Cluster);
}
TEST(RenderRef, FittedBevByConfidenceMatchesPillow) {
  check_bev("bev_confidence", 256, 256, 0.0, stixel::BevOptions::Color::Confidence);
}
