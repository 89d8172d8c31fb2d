#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include <Eigen/LU>

#include "geometry/camera.h"

namespace {

TEST(Camera, DepthFromDisparity) {
  double z = 0;
  ASSERT_TRUE(geometry::depth_from_disparity(8.0, 240.0, &z));
  EXPECT_DOUBLE_EQ(z, 30.0);
  ASSERT_TRUE(geometry::depth_from_disparity(1.0 / 32, 240.0, &z));
  EXPECT_DOUBLE_EQ(z, 7680.0);
  z = -1;
  EXPECT_FALSE(geometry::depth_from_disparity(0.0, 240.0, &z));
  EXPECT_FALSE(geometry::depth_from_disparity(-2.0, 240.0, &z));
  EXPECT_FALSE(geometry::depth_from_disparity(std::nan(""), 240.0, &z));
  EXPECT_FALSE(geometry::depth_from_disparity(std::numeric_limits<double>::infinity(), 240.0, &z));
  EXPECT_FALSE(geometry::depth_from_disparity(1e-310, 240.0, &z));  // overflows
  EXPECT_EQ(z, -1);  // untouched on failure
}

TEST(Camera, BackProjectionRoundTrips) {
  geometry::Intrinsics k{2000, 1900, 640, 360};
  Eigen::Vector3d p = geometry::back_project(900, 100, 25.0, k);
  EXPECT_DOUBLE_EQ(p.z(), 25.0);
  EXPECT_NEAR(k.cx + k.fx * p.x() / p.z(), 900, 1e-9);
  EXPECT_NEAR(k.cy + k.fy * p.y() / p.z(), 100, 1e-9);
  EXPECT_LT(p.y(), 0);  // above the principal point = up = negative camera y
}

TEST(Camera, LevelHeightIsReleasedFormula) {
  // H = 1.45 - (v - cy) Z / fy: a pixel 100 rows above cy at 20 m, f = 2000.
  EXPECT_NEAR(geometry::level_height(260, 20.0, 2000, 360, 1.45), 1.45 + 1.0, 1e-12);
  EXPECT_NEAR(geometry::level_height(360, 50.0, 2000, 360, 1.45), 1.45, 1e-12);
  EXPECT_NEAR(geometry::level_road_y(460, 20.0, 2000, 360, 1.45), 1.0 - 1.45, 1e-12);
}

TEST(Camera, LevelExtrinsicsMatchLevelFormula) {
  geometry::Intrinsics k{2000, 2000, 640, 360};
  geometry::Extrinsics e = geometry::Extrinsics::level(1.45);
  for (double v : {0.0, 200.0, 359.0, 500.0})
    for (double z : {5.0, 33.3, 70.0}) {
      Eigen::Vector3d p = geometry::back_project(100, v, z, k);
      EXPECT_NEAR(geometry::height_above_ground(p, e), geometry::level_height(v, z, k.fy, k.cy, 1.45), 1e-12);
    }
}

TEST(Camera, PitchedCameraSeesRoadPointAtZeroHeight) {
  // A camera pitched down 2 degrees, 1.5 m high: the optical axis meets the road
  // at 1.5 / tan(2 deg) along the road.
  const double pitch = 2.0 * M_PI / 180.0, h = 1.5;
  geometry::Extrinsics e = geometry::Extrinsics::pitched(pitch, h);
  const double along_axis = h / std::sin(pitch);  // camera depth of that road point
  Eigen::Vector3d p(0, 0, along_axis);
  EXPECT_NEAR(geometry::height_above_ground(p, e), 0.0, 1e-9);
  EXPECT_NEAR((e.rotation * p + e.translation).z(), h / std::tan(pitch), 1e-9);
  EXPECT_NEAR(e.rotation.determinant(), 1.0, 1e-12);
  // Straight up in the camera (negative y) is up in the road frame too.
  EXPECT_GT(geometry::height_above_ground(Eigen::Vector3d(0, -1, 0), e), h);
}

}  // namespace
