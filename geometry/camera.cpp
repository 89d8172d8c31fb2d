#include "geometry/camera.h"

#include <cmath>

namespace geometry {

Extrinsics Extrinsics::level(double mount_height) {
  Extrinsics e;
  e.translation = Eigen::Vector3d(0.0, -mount_height, 0.0);
  return e;
}

Extrinsics Extrinsics::pitched(double pitch_rad, double mount_height) {
  // Looking down by theta turns the optical axis towards +y (down) in the road
  // frame: road = Rx(theta) * cam with z_cam -> (0, sin, cos).
  Extrinsics e;
  double c = std::cos(pitch_rad), s = std::sin(pitch_rad);
  e.rotation << 1, 0, 0,
                0, c, s,
                0, -s, c;
  e.translation = Eigen::Vector3d(0.0, -mount_height, 0.0);
  return e;
}

}  // namespace geometry
