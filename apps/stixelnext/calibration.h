// The stixelnext calibration files. Two forms are read:
//   ours:      {"K": [9 numbers, row-major], "T": [16 numbers, row-major, optional: identity],
//               "width": W, "height": H}      W x H: the size of the images it belongs to
//   authors':  {"fx": F, "fy": F, "cx": C, "cy": C}   (StixelNExT_Pro's
//               load_camera_matrix_from_json: K = [[fx, 0, cx], [0, fy, cy], [0, 0, 1]],
//               T = identity; other keys are ignored as their loader does; the size is
//               the image's own; fx and fy must be positive)
// A file with any of fx, fy, cx, cy is the authors' form.
#pragma once

#include <string>
#include <vector>

namespace json {
class Value;
}

namespace stixelnext {

struct Calibration {
  std::vector<float> K, T;
  int width = 0, height = 0;  // 0 x 0 (the authors' form): whatever size the image has
  bool has_size() const { return width > 0 && height > 0; }
};

// Throws std::runtime_error("path: problem") on a malformed file (one line).
Calibration read_calibration(const std::string& path);
// The same on a parsed document; `source` names it in errors.
Calibration parse_calibration(const json::Value& doc, const std::string& source);

// <folder of image>/<stem of image>.json, where --calib-per-image looks.
std::string per_image_calibration_path(const std::string& image_path);

}  // namespace stixelnext
