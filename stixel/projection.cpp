#include "stixel/projection.h"

#include <Eigen/LU>
#include <cmath>
#include <string>

#include "stixel/error.h"

namespace stixel {
namespace {

void check_values(const std::vector<float>& v, const std::string& source, const char* name) {
  for (std::size_t i = 0; i < v.size(); ++i)
    if (!std::isfinite(v[i]))
      throw Error(source + ": " + name + "[" + std::to_string(i) + "] is not finite");
}

}  // namespace

Projection::Projection(const std::vector<float>& K, const std::vector<float>& T,
                       const std::string& source) {
  if (K.size() != 9)
    throw Error(source + ": K has " + std::to_string(K.size()) + " values, expected 9 (3x3)");
  if (!T.empty() && T.size() != 16)
    throw Error(source + ": T has " + std::to_string(T.size()) + " values, expected 16 (4x4)");
  check_values(K, source, "K");
  check_values(T, source, "T");
  Eigen::Matrix4d k4 = Eigen::Matrix4d::Identity();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) k4(r, c) = K[r * 3 + c];
  Eigen::Matrix4d t = Eigen::Matrix4d::Identity();
  if (!T.empty())
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) t(r, c) = T[r * 4 + c];
  const Eigen::Matrix4d p = k4 * t;
  // Full pivoting judges rank relative to the matrix's own scale, so a K4*T
  // that is singular up to rounding is rejected instead of inverted into garbage.
  Eigen::FullPivLU<Eigen::Matrix4d> lu(p);
  if (!lu.isInvertible())
    throw Error(source + ": K4 * T is singular (rank " + std::to_string(lu.rank()) +
                "); check K and T");
  inverse_ = lu.inverse();
}

Projection::Projection(const CameraInfo& calibration, const std::string& source)
    : Projection(calibration.K, calibration.T, source) {}

Point3 Projection::point(std::int32_t u, std::int32_t v, float d) const {
  const double ud = static_cast<float>(static_cast<float>(u) * d);
  const double vd = static_cast<float>(static_cast<float>(v) * d);
  const double w = d;
  const Eigen::Matrix4d& m = inverse_;
  Point3 p;
  p.x = m(0, 0) * ud + m(0, 1) * vd + m(0, 2) * w + m(0, 3);
  p.y = m(1, 0) * ud + m(1, 1) * vd + m(1, 2) * w + m(1, 3);
  p.z = m(2, 0) * ud + m(2, 1) * vd + m(2, 2) * w + m(2, 3);
  return p;
}

std::vector<Point3> top_points(const StixelWorld& world, const Projection& projection) {
  std::vector<Point3> out;
  out.reserve(world.stixels.size());
  for (const Stixel& s : world.stixels) out.push_back(projection.point(s.u, s.vT, s.d));
  return out;
}

std::vector<Point3> bottom_points(const StixelWorld& world, const Projection& projection) {
  std::vector<Point3> out;
  out.reserve(world.stixels.size());
  for (const Stixel& s : world.stixels) out.push_back(projection.point(s.u, s.vB, s.d));
  return out;
}

std::vector<Point3> point_cloud(const StixelWorld& world, const Projection& projection,
                                std::vector<int>* owner) {
  std::size_t total = 0;
  for (const Stixel& s : world.stixels)
    if (s.vB > s.vT) total += static_cast<std::size_t>(static_cast<std::int64_t>(s.vB) - s.vT);
  std::vector<Point3> out;
  out.reserve(total);
  if (owner) {
    owner->clear();
    owner->reserve(total);
  }
  for (std::size_t i = 0; i < world.stixels.size(); ++i) {
    const Stixel& s = world.stixels[i];
    for (std::int64_t v = s.vT; v < s.vB; ++v) {
      out.push_back(projection.point(s.u, static_cast<std::int32_t>(v), s.d));
      if (owner) owner->push_back(static_cast<int>(i));
    }
  }
  return out;
}

double focal_length_px(const std::vector<float>& K, const std::string& source) {
  if (K.size() != 9)
    throw Error(source + ": K has " + std::to_string(K.size()) + " values, expected 9 (3x3)");
  check_values(K, source, "K");
  Eigen::Matrix3d k;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) k(r, c) = K[r * 3 + c];
  // K = K_std * A with A orthogonal (identity, or the axis permutation of K_eff),
  // so K * K^T = K_std * K_std^T; read f_x, f_y off that upper-triangular factor.
  const Eigen::Matrix3d m = k * k.transpose();
  const double w = std::sqrt(m(2, 2));
  if (!(w > 0)) throw Error(source + ": K is degenerate (third row is zero)");
  const double cy = m(1, 2) / w, cx = m(0, 2) / w;
  const double fy2 = m(1, 1) - cy * cy;
  if (!(fy2 > 0)) throw Error(source + ": K is degenerate (no vertical focal length)");
  const double fy = std::sqrt(fy2);
  const double skew = (m(0, 1) - cx * cy) / fy;
  const double fx2 = m(0, 0) - skew * skew - cx * cx;
  if (!(fx2 > 0)) throw Error(source + ": K is degenerate (no horizontal focal length)");
  return (std::sqrt(fx2) + fy) / (2.0 * w);
}

double camera_depth_scale(const std::vector<float>& K, double train_focal,
                          const std::string& source) {
  if (!(train_focal > 0) || !std::isfinite(train_focal))
    throw Error("train focal length must be positive, got " + std::to_string(train_focal));
  return focal_length_px(K, source) / train_focal;
}

}  // namespace stixel
