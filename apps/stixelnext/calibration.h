// The stixelnext calibration file:
//   {"K": [9 numbers, row-major], "T": [16 numbers, row-major, optional: identity],
//    "width": W, "height": H}
// W x H is the size of the images the calibration belongs to.
#pragma once

#include <string>
#include <vector>

namespace json {
class Value;
}

namespace stixelnext {

struct Calibration {
  std::vector<float> K, T;
  int width = 0, height = 0;
};

// Throws std::runtime_error("path: problem") on a malformed file.
Calibration read_calibration(const std::string& path);
// The same on a parsed document; `source` names it in errors.
Calibration parse_calibration(const json::Value& doc, const std::string& source);

}  // namespace stixelnext
