#include <gtest/gtest.h>

#include "stixel/clustering.h"
#include "stixel/error.h"

namespace {

const std::vector<float> kK = {1000.0f, 0.0f, 500.0f, 0.0f, 1000.0f, 300.0f, 0.0f, 0.0f, 1.0f};

stixel::Stixel make(int u, int vT, int vB, float d, float conf = 0.5f) {
  stixel::Stixel s;
  s.u = u;
  s.vT = vT;
  s.vB = vB;
  s.d = d;
  s.width = 8;
  s.confidence = conf;
  return s;
}

}  // namespace

TEST(Clustering, LabelsStixelsAndStoresTheMaximumLabel) {
  stixel::StixelWorld w;
  // x = (u - 500) * d / 1000, z = d. Group A near x = 0, z = 10; group B at z = 30;
  // one isolated stixel.
  w.stixels = {make(500, 100, 200, 10.0f), make(540, 100, 200, 10.0f), make(520, 100, 200, 10.5f),
               make(500, 100, 200, 30.0f), make(520, 100, 200, 30.5f), make(900, 100, 200, 60.0f)};
  const stixel::Projection p(kK, {});
  stixel::cluster_stixels(w, p, {});
  std::vector<int> got;
  for (const auto& s : w.stixels) got.push_back(s.cluster);
  EXPECT_EQ(got, (std::vector<int>{0, 0, 0, 1, 1, -1}));
  EXPECT_EQ(w.context.clusters, 1);
  // The axes matter: two stixels at the same x and height (y) but 23 m apart in
  // depth (z) are one cluster on the x/y axes and two noise points on x/z.
  stixel::StixelWorld pair;
  pair.stixels = {make(500, 100, 200, 10.0f), make(500, 240, 260, 33.333f)};
  stixel::cluster_stixels(pair, p, {});
  EXPECT_EQ(pair.stixels[0].cluster, -1);
  EXPECT_EQ(pair.stixels[1].cluster, -1);
  stixel::ClusterOptions xy;
  xy.axis_b = 1;
  stixel::cluster_stixels(pair, p, xy);
  EXPECT_EQ(pair.stixels[0].cluster, 0);
  EXPECT_EQ(pair.stixels[1].cluster, 0);
  EXPECT_EQ(pair.context.clusters, 0);
  // All noise: the maximum label is -1.
  stixel::ClusterOptions strict;
  strict.min_samples = 10;
  stixel::cluster_stixels(w, p, strict);
  EXPECT_EQ(w.context.clusters, -1);
  for (const auto& s : w.stixels) EXPECT_EQ(s.cluster, -1);
  stixel::StixelWorld empty;
  stixel::cluster_stixels(empty, p, {});
  EXPECT_EQ(empty.context.clusters, -1);
}

TEST(Clustering, InvalidOptionsAreErrors) {
  stixel::StixelWorld w;
  w.stixels = {make(1, 1, 2, 5.0f)};
  const stixel::Projection p(kK, {});
  stixel::ClusterOptions o;
  o.axis_b = 0;
  EXPECT_THROW(stixel::cluster_stixels(w, p, o), stixel::Error);
  o.axis_b = 3;
  EXPECT_THROW(stixel::cluster_stixels(w, p, o), stixel::Error);
  EXPECT_THROW(stixel::cluster_stixels(w, std::vector<stixel::Point3>{}, {}), stixel::Error);
}

TEST(Clustering, BoxesEncloseTopAndBottomPoints) {
  stixel::StixelWorld w;
  w.stixels = {make(500, 100, 200, 10.0f, 0.4f), make(600, 150, 250, 12.0f, 0.8f),
               make(100, 0, 10, 20.0f, 0.9f), make(120, 5, 15, 20.0f, 0.1f), make(700, 10, 20, 5.0f, 1.0f)};
  w.stixels[0].cluster = 3;
  w.stixels[1].cluster = 3;
  w.stixels[2].cluster = 1;
  w.stixels[3].cluster = -1;
  w.stixels[4].cluster = 7;  // a single stixel: below min_cluster_size 2
  const stixel::Projection p(kK, {});
  std::vector<stixel::Box3D> boxes = stixel::boxes_from_clusters(w, p);
  ASSERT_EQ(boxes.size(), 1u);
  const stixel::Box3D& b = boxes[0];
  EXPECT_EQ(b.cluster_id, 3);
  EXPECT_EQ(b.num_stixels, 2);
  EXPECT_FLOAT_EQ(b.confidence, 0.6f);
  // x: (500-500)*10/1000 = 0 .. (600-500)*12/1000 = 1.2; y: (100-300)*10/1000 = -2
  // .. (250-300)*12/1000 = -0.6; z: 10 .. 12.
  const float x0 = 0.0f, x1 = 1.2f, y0 = -2.0f, y1 = -0.6f, z0 = 10.0f, z1 = 12.0f;
  const std::array<std::array<float, 3>, 8> expect = {{{x0, y0, z0}, {x1, y0, z0}, {x1, y1, z0}, {x0, y1, z0},
                                                      {x0, y0, z1}, {x1, y0, z1}, {x1, y1, z1}, {x0, y1, z1}}};
  for (int c = 0; c < 8; ++c)
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(b.corners[c][k], expect[c][k], 1e-5) << c << "," << k;

  boxes = stixel::boxes_from_clusters(w, p, 1, true);
  ASSERT_EQ(boxes.size(), 4u);
  EXPECT_EQ(boxes[0].cluster_id, -1);
  EXPECT_EQ(boxes[1].cluster_id, 1);
  EXPECT_EQ(boxes[2].cluster_id, 3);
  EXPECT_EQ(boxes[3].cluster_id, 7);
  EXPECT_EQ(boxes[0].num_stixels, 1);
  EXPECT_FLOAT_EQ(boxes[0].confidence, 0.1f);
  // Edges connect each bottom corner to its neighbours and to the top corner above.
  EXPECT_EQ(stixel::kBoxEdges[8][0], 0);
  EXPECT_EQ(stixel::kBoxEdges[8][1], 4);
}
