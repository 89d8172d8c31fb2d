// stixel/point_cloud: the points, their order, colours, labels and the PLY/CSV
// bytes (the comparison with pyStixel-lib's formulas is in stixelnext_cli_tests,
// StixelnextUsers.DefaultStx1AndPointsAreWhatPyStixelLibReads).
#include <gtest/gtest.h>

#include <cstring>

#include "stixel/error.h"
#include "stixel/point_cloud.h"

namespace {

stixel::StixelWorld two_stixels() {
  stixel::StixelWorld w;
  stixel::Stixel a;
  a.u = 8, a.vT = 2, a.vB = 5, a.d = 10.0f, a.cluster = 0;
  stixel::Stixel b;
  b.u = 16, b.vT = 7, b.vB = 7, b.d = 20.0f, b.cluster = -1;  // no rows
  stixel::Stixel c;
  c.u = 30, c.vT = 3, c.vB = 5, c.d = 5.0f, c.cluster = 1;  // u beyond the 20-px image: edge colour
  w.stixels = {a, b, c};
  w.context.clusters = 1;
  return w;
}

const stixel::Projection kCamera({100, 0, 10, 0, 100, 4, 0, 0, 1}, {});

TEST(PointCloud, PointsOrderIndicesColoursAndLabels) {
  stixel::RgbImage img;
  img.width = 20, img.height = 6;
  img.pixels.resize(20 * 6 * 3);
  for (std::size_t i = 0; i < img.pixels.size(); ++i) img.pixels[i] = static_cast<std::uint8_t>(i % 251);
  stixel::PointCloudOptions o;
  o.image = &img;
  o.cluster_labels = true;
  const auto c = stixel::world_point_cloud(two_stixels(), kCamera, o);
  ASSERT_EQ(c.xyz.size(), 5u);  // rows 2, 3, 4 of the first, 3, 4 of the third
  EXPECT_EQ(c.stixel, (std::vector<std::int32_t>{0, 0, 0, 2, 2}));
  EXPECT_EQ(c.cluster, (std::vector<std::int32_t>{0, 0, 0, 1, 1}));
  // (u - cx) * d / f, (v - cy) * d / f, d
  EXPECT_NEAR(c.xyz[0].x, (8 - 10) * 10.0 / 100, 1e-12);
  EXPECT_NEAR(c.xyz[0].y, (2 - 4) * 10.0 / 100, 1e-12);
  EXPECT_NEAR(c.xyz[0].z, 10.0, 1e-12);
  auto px = [&](int x, int y) {
    const std::uint8_t* p = &img.pixels[(static_cast<std::size_t>(y) * 20 + x) * 3];
    return stixel::Rgb{p[0], p[1], p[2]};
  };
  EXPECT_EQ(c.color[1], px(8, 3));
  EXPECT_EQ(c.color[3], px(19, 3));
  // Without an image a clustered world is coloured by cluster, as pyStixel-lib does.
  const auto j = stixel::world_point_cloud(two_stixels(), kCamera, {});
  ASSERT_EQ(j.color.size(), 5u);
  EXPECT_EQ(j.color[0], stixel::cluster_color(0, 1));
  EXPECT_EQ(j.color[4], stixel::cluster_color(1, 1));
  EXPECT_TRUE(j.cluster.empty());
  stixel::RgbImage bad = img;
  bad.pixels.pop_back();
  o.image = &bad;
  EXPECT_THROW(stixel::world_point_cloud(two_stixels(), kCamera, o), stixel::Error);
}

TEST(PointCloud, PlyAndCsvBytes) {
  auto w = two_stixels();
  w.context.clusters = -1;
  stixel::PointCloudOptions o;
  o.cluster_labels = true;
  const auto c = stixel::world_point_cloud(w, kCamera, o);
  const auto ply = stixel::to_ply(c, "name\nwith a newline");
  const std::string text(ply.begin(), ply.end());
  const std::string header =
      "ply\nformat binary_little_endian 1.0\ncomment name with a newline\nelement vertex 5\n"
      "property float x\nproperty float y\nproperty float z\nproperty int stixel\nproperty int cluster\nend_header\n";
  ASSERT_EQ(text.substr(0, header.size()), header);
  ASSERT_EQ(ply.size(), header.size() + 5 * 20);
  float z;
  std::memcpy(&z, &ply[header.size() + 8], 4);  // little-endian host
  EXPECT_EQ(z, 10.0f);
  std::int32_t owner;
  std::memcpy(&owner, &ply[header.size() + 4 * 20 + 12], 4);
  EXPECT_EQ(owner, 2);
  const std::string csv = stixel::to_points_csv(c);
  EXPECT_EQ(csv.substr(0, csv.find('\n', csv.find('\n') + 1) + 1), "x,y,z,stixel,cluster\n-0.2,-0.2,10,0,0\n");
}

}  // namespace
