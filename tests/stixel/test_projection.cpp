#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>

#include "stixel/error.h"
#include "stixel/projection.h"

namespace {

const std::vector<float> kStdK = {2000.0f, 0.0f, 960.0f, 0.0f, 2010.0f, 640.0f, 0.0f, 0.0f, 1.0f};

// Waymo K_eff = [[c_u, -f_u, 0], [c_v, 0, -f_v], [1, 0, 0]] for f 2081.253,
// c (954.130, 664.492), and T = inverse of a camera 1.54 m forward, 2.11 m up.
const std::vector<float> kEffK = {954.130f, -2081.253f, 0.0f, 664.492f, 0.0f, -2081.253f, 1.0f, 0.0f, 0.0f};
const std::vector<float> kVehicleToCamera = {1, 0, 0, -1.545f, 0, 1, 0, 0.050f, 0, 0, 1, -2.115f, 0, 0, 0, 1};

// Projects X with K4 * T back to (u, v, w).
Eigen::Vector3d project(const std::vector<float>& K, const std::vector<float>& T, const stixel::Point3& X) {
  Eigen::Matrix4d k4 = Eigen::Matrix4d::Identity(), t = Eigen::Matrix4d::Identity();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) k4(r, c) = K[r * 3 + c];
  if (!T.empty())
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) t(r, c) = T[r * 4 + c];
  const Eigen::Vector4d h = k4 * t * Eigen::Vector4d(X.x, X.y, X.z, 1.0);
  return {h(0) / h(2), h(1) / h(2), h(2)};
}

}  // namespace

TEST(Projection, OpticalFrameWithIdentityT) {
  const stixel::Projection p(kStdK, {});
  const stixel::Point3 X = p.point(960, 640, 20.0f);  // principal point
  EXPECT_NEAR(X.x, 0.0, 1e-12);
  EXPECT_NEAR(X.y, 0.0, 1e-12);
  EXPECT_NEAR(X.z, 20.0, 1e-12);
  const stixel::Point3 Y = p.point(1960, 1645, 10.0f);
  EXPECT_NEAR(Y.x, 1000.0 * 10 / 2000, 1e-9);  // x right
  EXPECT_NEAR(Y.y, 1005.0 * 10 / 2010, 1e-9);  // y down
  EXPECT_NEAR(Y.z, 10.0, 1e-12);
}

TEST(Projection, VehicleFrameRoundTripsThroughKT) {
  const stixel::Projection p(kEffK, kVehicleToCamera);
  for (int u : {0, 480, 1919})
    for (int v : {1, 640, 1280})
      for (float d : {4.0f, 17.5f, 66.0f}) {
        const stixel::Point3 X = p.point(u, v, d);
        const Eigen::Vector3d uvw = project(kEffK, kVehicleToCamera, X);
        EXPECT_NEAR(uvw(0), u, 1e-6 * 2000);
        EXPECT_NEAR(uvw(1), v, 1e-6 * 2000);
        EXPECT_NEAR(uvw(2), d, 1e-9 * 66);
        // d is the distance along the camera's forward axis (vehicle x), offset
        // by the camera position.
        EXPECT_NEAR(X.x, d + 1.545, 1e-4);
      }
  // Straight ahead at the principal point: on the optical axis, 2.11 m up.
  const stixel::Point3 c = p.point(954, 664, 30.0f);
  EXPECT_NEAR(c.z, 2.115, 0.02);
}

TEST(Projection, PointCloudRowsAreHalfOpen) {
  stixel::StixelWorld w;
  stixel::Stixel a;
  a.u = 100;
  a.vT = 10;
  a.vB = 14;
  a.d = 12.0f;
  stixel::Stixel empty = a;
  empty.vB = 10;
  stixel::Stixel inverted = a;
  inverted.vB = 5;
  stixel::Stixel b = a;
  b.vT = 20;
  b.vB = 22;
  w.stixels = {a, empty, inverted, b};
  const stixel::Projection p(kStdK, {});
  std::vector<int> owner;
  const auto cloud = stixel::point_cloud(w, p, &owner);
  ASSERT_EQ(cloud.size(), 6u);
  EXPECT_EQ(owner, (std::vector<int>{0, 0, 0, 0, 3, 3}));
  const auto top = stixel::top_points(w, p);
  const auto bottom = stixel::bottom_points(w, p);
  ASSERT_EQ(top.size(), 4u);
  EXPECT_EQ(cloud[0].y, top[0].y);
  EXPECT_EQ(cloud[4].y, top[3].y);
  EXPECT_NEAR(cloud[3].y, p.point(100, 13, 12.0f).y, 0);
  EXPECT_GT(bottom[0].y, top[0].y);  // optical frame: y grows downwards
}

TEST(Projection, ImageVectorIsFormedInFloat32) {
  // pyStixel-lib multiplies u and v by d in float32; 1917 * 33.3f is not exact.
  const stixel::Projection p(kStdK, {});
  const float d = 33.3f;
  const double ud = static_cast<float>(1917.0f * d);
  const stixel::Point3 X = p.point(1917, 0, d);
  EXPECT_DOUBLE_EQ(X.x, (ud - 960.0 * d) / 2000.0);
}

TEST(Projection, BadCalibrationsAreErrors) {
  auto expect_error = [](const std::vector<float>& K, const std::vector<float>& T, const std::string& needle) {
    try {
      stixel::Projection p(K, T, "calib.json");
      ADD_FAILURE() << "accepted, expected " << needle;
    } catch (const stixel::Error& e) {
      const std::string msg = e.what();
      EXPECT_EQ(msg.rfind("calib.json: ", 0), 0u) << msg;
      EXPECT_NE(msg.find(needle), std::string::npos) << msg;
    }
  };
  expect_error({1, 2, 3}, {}, "K has 3 values, expected 9");
  expect_error(kStdK, {1, 0, 0, 1}, "T has 4 values, expected 16");
  expect_error({0, 0, 0, 0, 0, 0, 0, 0, 0}, {}, "singular");
  expect_error({1, 2, 3, 2, 4, 6, 0, 0, 1}, {}, "singular");  // rows 0 and 1 parallel
  std::vector<float> T0(16, 0.0f);
  expect_error(kStdK, T0, "singular");
  std::vector<float> nan_k = kStdK;
  nan_k[4] = NAN;
  expect_error(nan_k, {}, "K[4] is not finite");
  stixel::CameraInfo info;
  info.K = kStdK;
  EXPECT_NO_THROW(stixel::Projection{info});
}

TEST(Projection, FocalLengthOfStandardAndWaymoK) {
  EXPECT_NEAR(stixel::focal_length_px(kStdK), 2005.0, 1e-3);
  EXPECT_NEAR(stixel::focal_length_px(kEffK), 2081.253, 1e-3);
  // Scale-invariant: K and 2K describe the same camera.
  std::vector<float> k2 = kStdK;
  for (float& v : k2) v *= 2;
  EXPECT_NEAR(stixel::focal_length_px(k2), 2005.0, 1e-3);
  EXPECT_NEAR(stixel::camera_depth_scale(kEffK, 2081.253 / 2), 2.0, 1e-6);
  EXPECT_THROW(stixel::focal_length_px({1, 0, 0, 0, 1, 0, 0, 0, 0}), stixel::Error);
  EXPECT_THROW(stixel::focal_length_px({1, 0}), stixel::Error);
  EXPECT_THROW(stixel::camera_depth_scale(kStdK, 0.0), stixel::Error);
}
