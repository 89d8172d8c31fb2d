// Camera calibration for the height stage, from a small JSON file
//   {"fx": 2000, "fy": 2000, "cx": 640, "cy": 360, "bf": 240.0,
//    "mount_height": 1.45, "disparity_scale": 32}
// ("baseline" in metres instead of "bf": bf = baseline * fx), or from the released
// code's SmarterEye calibData.json / DepthCalib.json pair.
#pragma once

#include <cstdint>

#include <string>

#include "geometry/camera.h"

namespace json {
class Value;
}

namespace shle {

struct Calibration {
  geometry::Intrinsics intrinsics;
  double bf = 240.0;              // baseline x focal length, metre-pixels
  double mount_height = 1.45;     // camera height above the road, metres
  double disparity_scale = 32.0;  // 16-bit PNG disparity = value / disparity_scale
  int width = 1280, height = 720; // size of headerless .dat disparity files
  // Optional camera-to-road transform; without it the camera is level at
  // mount_height and heights use the released code's formula.
  bool has_extrinsics = false;
  geometry::Extrinsics extrinsics;
};

// Largest calibrated image (width x height), 256 Mpx: above any camera, and the
// .dat disparity reader allocates width x height samples from it.
constexpr std::uint64_t kMaxCalibratedPixels = std::uint64_t(256) << 20;

// Plain format. Required: fx, fy, cx, cy and exactly one of bf / baseline.
// Optional: mount_height (1.45), disparity_scale (32), width/height (1280x720),
// rotation (3x3 nested array, camera->road, y down) with translation (3 numbers)
// replacing mount_height. Unknown keys are errors (they are usually typos).
// Throws shle::Error "<source>: <problem>".
Calibration parse_calibration(const json::Value& root, const std::string& source);
Calibration load_calibration(const std::string& path);

// The released code's `readCamera` layout: `path` is the adas_params folder or
// its calibData.json; DepthCalib.json must be beside it (names matched
// case-insensitively). fx = calib[4], fy = calib[12], cy = (calib[40] + calib[42]) / 2,
// cx = (calib[39] + calib[41]) / 2 - floor(depth[4] + depth[0]). bf, mount height,
// disparity scale and size are the released constants (240, 1.45, 32, 1280x720).
Calibration load_smartereye_calibration(const std::string& path);
// The same from the two parsed files; the sources name them in errors.
Calibration parse_smartereye_calibration(const json::Value& calib_data, const std::string& calib_source,
                                         const json::Value& depth_calib, const std::string& depth_source);

}  // namespace shle
