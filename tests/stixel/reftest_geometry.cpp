// 3D points, boxes and depth maps against pyStixel-lib's formulas in numpy
// (tests/reference/stixel_geometry_ref.py).
#include <cmath>

#include "stixel/clustering.h"
#include "stixel/depth_map.h"
#include "stixel/projection.h"
#include "tests/stixel/reftest_util.h"

namespace {

struct Case {
  weights::SafeTensors st;
  stixel::StixelWorld world;
};

Case load_case(const std::string& name) {
  Case c{stxref::load("stixel_geometry_" + name + ".safetensors"), {}};
  c.world.stixels = stxref::stixels(c.st);
  c.world.context.calibration.K = c.st.f32("K");
  c.world.context.calibration.T = c.st.f32("T");
  c.world.context.calibration.width = std::stoi(stxref::meta(c.st, "image_width"));
  c.world.context.calibration.height = std::stoi(stxref::meta(c.st, "image_height"));
  return c;
}

// Points agree to 1e-12 relative to the scene scale: only the summation order of
// the 4x4 product and the inverse's rounding differ.
void expect_points(const std::vector<stixel::Point3>& got, const std::vector<double>& ref, const char* what) {
  ASSERT_EQ(got.size() * 3, ref.size()) << what;
  double worst = 0;
  for (std::size_t i = 0; i < got.size(); ++i)
    for (int k = 0; k < 3; ++k)
      worst = std::max(worst, std::fabs(got[i][k] - ref[3 * i + k]) / std::max(1.0, std::fabs(ref[3 * i + k])));
  EXPECT_LE(worst, 1e-12) << what;
}

void check_points(const std::string& name) {
  SCOPED_TRACE(name);
  const Case c = load_case(name);
  const stixel::Projection p(c.world.context.calibration);
  expect_points(stixel::top_points(c.world, p), stxref::f64(c.st, "top"), "top");
  expect_points(stixel::bottom_points(c.world, p), stxref::f64(c.st, "bottom"), "bottom");
  expect_points(stixel::point_cloud(c.world, p), stxref::f64(c.st, "cloud"), "point cloud");
}

void check_boxes(const std::string& name) {
  SCOPED_TRACE(name);
  const Case c = load_case(name);
  const stixel::Projection p(c.world.context.calibration);
  for (const std::string tag : {"boxes", "boxes_all"}) {
    const auto boxes = tag == "boxes" ? stixel::boxes_from_clusters(c.world, p)
                                      : stixel::boxes_from_clusters(c.world, p, 1, true);
    const auto id = stxref::i32(c.st, tag + "_id"), count = stxref::i32(c.st, tag + "_count");
    const auto conf = c.st.f32(tag + "_confidence"), corners = c.st.f32(tag + "_corners");
    ASSERT_EQ(boxes.size(), id.size()) << tag;
    for (std::size_t b = 0; b < boxes.size(); ++b) {
      EXPECT_EQ(boxes[b].cluster_id, id[b]);
      EXPECT_EQ(boxes[b].num_stixels, count[b]);
      EXPECT_EQ(boxes[b].confidence, conf[b]);
      for (int k = 0; k < 8; ++k)
        for (int j = 0; j < 3; ++j) {
          const float r = corners[(b * 8 + k) * 3 + j];
          // float32 corners from float64 extremes: equal up to one float rounding.
          EXPECT_LE(std::fabs(boxes[b].corners[k][j] - r), 1e-6f * std::max(1.0f, std::fabs(r)))
              << tag << " box " << b << " corner " << k;
        }
    }
  }
}

void check_depth_map(const std::string& name) {
  SCOPED_TRACE(name);
  const Case c = load_case(name);
  const stixel::DepthMap m = stixel::depth_map(c.world);
  const auto& shape = c.st.info("depth_map").shape;
  ASSERT_EQ(m.height, shape[0]);
  ASSERT_EQ(m.width, shape[1]);
  const std::vector<float> ref = c.st.f32("depth_map");
  int covered = 0, mismatches = 0;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    const bool same = std::isnan(ref[i]) ? std::isnan(m.depth[i]) : m.depth[i] == ref[i];
    covered += !std::isnan(ref[i]);
    if (!same && mismatches++ < 5) ADD_FAILURE() << "pixel " << i << ": " << m.depth[i] << " vs " << ref[i];
  }
  EXPECT_EQ(mismatches, 0);
  EXPECT_GT(covered, 1000);
}

}  // namespace

TEST(GeometryRef, PointsOpticalFrame) { check_points("optical"); }
TEST(GeometryRef, PointsWaymoVehicleFrame) { check_points("waymo"); }
TEST(GeometryRef, BoxesOpticalFrame) { check_boxes("optical"); }
TEST(GeometryRef, BoxesWaymoVehicleFrame) { check_boxes("waymo"); }
TEST(GeometryRef, DepthMap) { check_depth_map("optical"); }
