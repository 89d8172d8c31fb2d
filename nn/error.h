// Errors the runtime reports to its caller. Messages are one line, naming the
// file or tensor and the problem; the apps print them and exit non-zero.
#pragma once

#include <stdexcept>
#include <string>

namespace nn {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& what) : std::runtime_error(what) {}
};

}  // namespace nn
