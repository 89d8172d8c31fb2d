// The Stixel World data model, field for field the protobuf messages of
// pyStixel-lib (package stixelworld, proto3) so that a .stx1 file round-trips
// without loss. Defaults are the proto3 defaults (0, 0.0, empty).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace stixel {

// One obstacle slice in one image column.
struct Stixel {
  std::int32_t u = 0;         // column centre (px)
  std::int32_t vT = 0;        // top row (px)
  std::int32_t vB = 0;        // bottom row (px)
  float d = 0.0f;             // depth = projective w along the optical axis (m)
  std::int32_t label = 0;     // Segmentation.Type (0..22), or a Waymo box type
  std::int32_t width = 0;     // px
  float confidence = 0.0f;    // existence probability P
  std::int32_t idx = 0;       // unique id (0 when unused)
  std::int32_t cluster = 0;   // cluster id after clustering; -1 = noise
};

enum DistortionModel : std::int32_t { kModelUndefined = 0, kModelPlumbBob = 1 };

// Camera calibration. Matrices are row-major; empty vectors mean "not given".
struct CameraInfo {
  std::vector<float> K;  // 3x3 intrinsics (9 values)
  std::vector<float> T;  // 4x4 [R|t], world/vehicle -> camera (16 values)
  std::vector<float> R;  // 4x4 rectification
  std::vector<float> D;  // distortion (k1, k2, t1, t2, k3); ignored by all geometry
  std::int32_t distortion_model = kModelUndefined;
  std::string reference;  // e.g. "Vehicle2Camera"
  std::string img_name;
  std::int32_t width = 0, height = 0, channels = 0;
};

struct Context {
  std::string name;         // files are saved as <name>.stx1
  CameraInfo calibration;
  std::int32_t clusters = 0;  // maximum cluster label (not the count); -1 = no cluster
  // proto3 keeps the presence of sub-messages: a calibration message that was
  // present but empty is written back. Setting any calibration field also makes
  // it present; this flag only matters for an all-default calibration.
  bool has_calibration = false;
};

struct StixelWorld {
  std::vector<Stixel> stixels;
  std::vector<std::uint8_t> image;  // encoded PNG or JPEG (identified by magic), or empty
  Context context;
  bool has_context = false;  // as Context::has_calibration, for an all-default context
};

// Keeps the stixels with confidence >= min_confidence (pyStixel-lib's
// filter_stixels_by_confidence); min_confidence must lie in [0, 1].
void filter_by_confidence(StixelWorld& world, double min_confidence);

}  // namespace stixel
