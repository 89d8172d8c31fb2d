// The error the SHLE library throws: one line naming the file (or frame) and the
// problem, e.g. "seq/disparity_images/disparity_5_a_b_c_d.dat: 1843100 bytes,
// expected 1843200 (1280x720 uint16)". The apps print it and go on with the next
// frame, or exit 1 when nothing can be done (bad calibration, empty sequence).
#pragma once

#include <stdexcept>
#include <string>

namespace shle {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& what) : std::runtime_error(what) {}
};

}  // namespace shle
