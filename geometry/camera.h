// Stereo camera geometry: disparity to depth, pinhole back-projection and height
// above the road. Camera frame: x right, y DOWN, z forward (the released SHLE
// convention). The road frame has the same axes with its origin on the road
// surface, so a level camera mounted h metres high sits at road y = -h.
#pragma once

#include <Eigen/Core>

namespace geometry {

struct Intrinsics {
  double fx = 0, fy = 0, cx = 0, cy = 0;
};

// Depth Z = bf / d (bf in metre-pixels, d in pixels). Returns false for an invalid
// disparity: d <= 0, NaN or infinite, or a quotient that is not finite (d so small
// that bf / d overflows).
inline bool depth_from_disparity(double d, double bf, double* z) {
  if (!(d > 0.0) || !(d < 1e300)) return false;
  double q = bf / d;
  if (!(q > -1e308 && q < 1e308)) return false;
  *z = q;
  return true;
}

// Camera-frame point of pixel (u, v) at depth z: X = (u - cx) z / fx,
// Y = (v - cy) z / fy, Z = z. Pixel coordinates are used as given (the released
// code uses integer pixel indices, no +0.5).
inline Eigen::Vector3d back_project(double u, double v, double z, const Intrinsics& k) {
  return Eigen::Vector3d((u - k.cx) * z / k.fx, (v - k.cy) * z / k.fy, z);
}

// Rigid transform from the camera frame to the road frame: p_road = R p_cam + t.
struct Extrinsics {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  // A level camera (no pitch, roll or yaw) mounted `mount_height` above the road.
  static Extrinsics level(double mount_height);
  // A camera pitched by `pitch_rad` (positive = looking down) about its x axis,
  // mounted `mount_height` above the road.
  static Extrinsics pitched(double pitch_rad, double mount_height);
};

// Height above the road of a camera-frame point: minus the road-frame y.
inline double height_above_ground(const Eigen::Vector3d& p_cam, const Extrinsics& e) {
  return -(e.rotation.row(1).dot(p_cam) + e.translation.y());
}

// The released code's road-frame y for a level camera, in its exact order of
// operations: Y = (v - cy) * Z / fy - mount_height. Height above ground is -Y.
inline double level_road_y(double v, double z, double fy, double cy, double mount_height) {
  return (v - cy) * z / fy - mount_height;
}

// Height above ground for a level camera: H = mount_height - (v - cy) Z / fy.
inline double level_height(double v, double z, double fy, double cy, double mount_height) {
  return -level_road_y(v, z, fy, cy, mount_height);
}

}  // namespace geometry
