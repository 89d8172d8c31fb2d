#include "shle/calibration.h"

#include "weights/quote_name.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <set>

#include <Eigen/LU>

#include "shle/error.h"
#include "weights/json.h"

namespace shle {
namespace {

namespace fs = std::filesystem;

double number(const json::Value& root, const char* key, const std::string& source) {
  const json::Value* v = root.get(key);
  if (!v || !v->is_number()) throw Error(source + ": '" + key + "' must be a number");
  double x = v->number();
  if (!std::isfinite(x)) throw Error(source + ": '" + key + "' is not finite");
  return x;
}

double positive(const json::Value& root, const char* key, const std::string& source) {
  double x = number(root, key, source);
  if (!(x > 0)) throw Error(source + ": '" + key + "' must be > 0");
  return x;
}

int image_size(const json::Value& root, const char* key, const std::string& source) {
  double x = number(root, key, source);
  if (x != std::floor(x) || x < 1 || x > 65535)
    throw Error(source + ": '" + key + "' must be an integer in 1..65535");
  return static_cast<int>(x);
}

std::vector<double> numbers(const json::Value& v, std::size_t n, const std::string& what,
                            const std::string& source) {
  if (!v.is_array() || v.array().size() != n)
    throw Error(source + ": '" + what + "' must be an array of " + std::to_string(n) + " numbers");
  std::vector<double> out;
  for (const json::Value& e : v.array()) {
    if (!e.is_number() || !std::isfinite(e.number()))
      throw Error(source + ": '" + what + "' must hold finite numbers");
    out.push_back(e.number());
  }
  return out;
}

json::Value parse_json_file(const std::string& path) {
  try {
    return json::parse_file(path);
  } catch (const json::Error& e) {
    throw Error(e.what());
  }
}

}  // namespace

Calibration parse_calibration(const json::Value& root, const std::string& source) {
  if (!root.is_object()) throw Error(source + ": calibration must be a JSON object");
  static const std::set<std::string> known = {"fx", "fy", "cx", "cy", "bf", "baseline",
                                              "mount_height", "disparity_scale", "width",
                                              "height", "rotation", "translation"};
  for (const auto& m : root.object())
    if (!known.count(m.first))
      throw Error(source + ": unknown key " + weights::quote_name(m.first) + " (known: fx, fy, cx, cy, bf, baseline, "
                  "mount_height, disparity_scale, width, height, rotation, translation)");
  Calibration c;
  c.intrinsics.fx = positive(root, "fx", source);
  c.intrinsics.fy = positive(root, "fy", source);
  c.intrinsics.cx = number(root, "cx", source);
  c.intrinsics.cy = number(root, "cy", source);
  bool has_bf = root.get("bf") != nullptr, has_baseline = root.get("baseline") != nullptr;
  if (has_bf == has_baseline)
    throw Error(source + ": give exactly one of 'bf' (metre-pixels) and 'baseline' (metres)");
  c.bf = has_bf ? positive(root, "bf", source) : positive(root, "baseline", source) * c.intrinsics.fx;
  if (!std::isfinite(c.bf))
    throw Error(source + ": 'baseline' x 'fx' overflows to infinity (" + std::to_string(c.bf) + ")");
  if (root.get("disparity_scale")) c.disparity_scale = positive(root, "disparity_scale", source);
  if (root.get("width")) c.width = image_size(root, "width", source);
  if (root.get("height")) c.height = image_size(root, "height", source);
  if (std::uint64_t(c.width) * std::uint64_t(c.height) > kMaxCalibratedPixels)
    throw Error(source + ": 'width' x 'height' is " + std::to_string(c.width) + "x" + std::to_string(c.height) +
                ", above the limit of " + std::to_string(kMaxCalibratedPixels >> 20) + " Mpx");
  const json::Value* rot = root.get("rotation");
  const json::Value* tr = root.get("translation");
  if ((rot == nullptr) != (tr == nullptr))
    throw Error(source + ": 'rotation' and 'translation' go together");
  if (rot) {
    if (root.get("mount_height"))
      throw Error(source + ": give either 'mount_height' or 'rotation'/'translation', not both");
    if (!rot->is_array() || rot->array().size() != 3)
      throw Error(source + ": 'rotation' must be a 3x3 nested array");
    Eigen::Matrix3d r;
    for (int i = 0; i < 3; ++i) {
      std::vector<double> row = numbers(rot->array()[i], 3, "rotation", source);
      for (int j = 0; j < 3; ++j) r(i, j) = row[j];
    }
    if (!((r * r.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-6) ||
        !(r.determinant() > 0))
      throw Error(source + ": 'rotation' is not a rotation matrix (orthonormal, det +1)");
    std::vector<double> t = numbers(*tr, 3, "translation", source);
    c.has_extrinsics = true;
    c.extrinsics.rotation = r;
    c.extrinsics.translation = Eigen::Vector3d(t[0], t[1], t[2]);
    c.mount_height = -t[1];
  } else if (root.get("mount_height")) {
    c.mount_height = number(root, "mount_height", source);
  }
  return c;
}

Calibration load_calibration(const std::string& path) {
  return parse_calibration(parse_json_file(path), path);
}

Calibration load_smartereye_calibration(const std::string& path) {
  std::error_code ec;
  fs::path dir = fs::is_directory(path, ec) ? fs::path(path) : fs::path(path).parent_path();
  if (dir.empty()) dir = ".";
  auto find = [&](const std::string& want) -> std::string {
    std::string lw = want;
    std::transform(lw.begin(), lw.end(), lw.begin(), [](unsigned char ch) { return std::tolower(ch); });
    std::error_code e2;
    for (fs::directory_iterator it(dir, e2), end; !e2 && it != end; it.increment(e2)) {
      std::string name = it->path().filename().string();
      std::transform(name.begin(), name.end(), name.begin(), [](unsigned char ch) { return std::tolower(ch); });
      if (name == lw) return it->path().string();
    }
    if (e2) throw Error(dir.string() + ": cannot list (" + e2.message() + ")");
    throw Error(dir.string() + ": no " + want + " (SmarterEye calibration needs calibData.json and DepthCalib.json)");
  };
  std::string calib_path = find("calibData.json"), depth_path = find("DepthCalib.json");
  json::Value calib_data = parse_json_file(calib_path);
  json::Value depth_calib = parse_json_file(depth_path);
  return parse_smartereye_calibration(calib_data, calib_path, depth_calib, depth_path);
}

Calibration parse_smartereye_calibration(const json::Value& calib_data, const std::string& calib_source,
                                         const json::Value& depth_calib, const std::string& depth_source) {
  auto data = [](const json::Value& root, const std::string& p, std::size_t need) {
    const json::Value* d = root.is_object() ? root.get("data") : nullptr;
    if (!d || !d->is_array()) throw Error(p + ": expected an object with a \"data\" array");
    if (d->array().size() < need)
      throw Error(p + ": \"data\" has " + std::to_string(d->array().size()) + " entries, need at least " +
                  std::to_string(need));
    std::vector<double> out;
    for (const json::Value& e : d->array()) {
      if (!e.is_number() || !std::isfinite(e.number())) throw Error(p + ": \"data\" must hold finite numbers");
      out.push_back(e.number());
    }
    return out;
  };
  std::vector<double> cd = data(calib_data, calib_source, 43), dc = data(depth_calib, depth_source, 5);
  Calibration c;
  c.intrinsics.fx = cd[4];
  c.intrinsics.fy = cd[12];
  c.intrinsics.cy = (cd[40] + cd[42]) / 2.0;
  c.intrinsics.cx = (cd[39] + cd[41]) / 2.0 - std::floor(dc[4] + dc[0]);
  if (!(c.intrinsics.fx > 0) || !(c.intrinsics.fy > 0))
    throw Error(calib_source + ": focal lengths data[4] and data[12] must be > 0");
  if (!std::isfinite(c.intrinsics.cx) || !std::isfinite(c.intrinsics.cy))
    throw Error(calib_source + ": the principal point (data[39..42] with DepthCalib data[0], data[4]) overflows to infinity");
  return c;
}

}  // namespace shle
