// Image (u, v, d) -> 3D exactly as pyStixel-lib computes it:
//   X_h = inverse(K4 * T) * [u*d, v*d, d, 1],  K4 = 4x4 identity with K top-left.
// With Waymo's K_eff and T = inverse(extrinsic) X is in the vehicle frame
// (x forward, y left, z up); with a standard K and T = I it is the optical camera
// frame (x right, y down, z forward).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "stixel/world.h"

namespace stixel {

struct Point3 {
  double x = 0, y = 0, z = 0;
  double operator[](int axis) const { return axis == 0 ? x : axis == 1 ? y : z; }
};

class Projection {
 public:
  // K: 9 values (3x3 row-major); T: 16 values (4x4 row-major) or empty for the
  // identity. Throws Error naming `source` if a size is wrong, a value is not
  // finite, or K4 * T is singular.
  Projection(const std::vector<float>& K, const std::vector<float>& T,
             const std::string& source = "calibration");
  explicit Projection(const CameraInfo& calibration, const std::string& source = "calibration");

  // The homogeneous image vector is formed in float32 like pyStixel-lib
  // (u*d and v*d rounded to float), the product with the inverse in double.
  Point3 point(std::int32_t u, std::int32_t v, float d) const;

  const Eigen::Matrix4d& inverse() const { return inverse_; }

 private:
  Eigen::Matrix4d inverse_;
};

// One point per stixel at (u, vT, d): what clustering and the bird's-eye view use.
std::vector<Point3> top_points(const StixelWorld& world, const Projection& projection);
// One point per stixel at (u, vB, d).
std::vector<Point3> bottom_points(const StixelWorld& world, const Projection& projection);

// One point per image row v in [vT, vB) of every stixel (none if vB <= vT), in
// stixel order, all at the stixel's u (no width offset). If `owner` is given it
// receives the stixel index of every point.
std::vector<Point3> point_cloud(const StixelWorld& world, const Projection& projection,
                                std::vector<int>* owner = nullptr);

// The focal length in pixels of a 3x3 K, (f_x + f_y) / 2, valid for a standard K
// and for Waymo's axis-permuted K_eff alike (taken from K * K^T, which is the same
// for both). Throws Error if K is degenerate.
double focal_length_px(const std::vector<float>& K, const std::string& source = "calibration");

// Focal-length adaptation: depth scale f_camera / train_focal for a network
// trained on images of focal length `train_focal` pixels.
double camera_depth_scale(const std::vector<float>& K, double train_focal,
                          const std::string& source = "calibration");

}  // namespace stixel
