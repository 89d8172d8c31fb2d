// The error the geometry library throws for arguments it cannot work with
// (non-finite samples, non-positive bandwidth, ...). One line, naming the problem.
#pragma once

#include <stdexcept>
#include <string>

namespace geometry {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& what) : std::runtime_error(what) {}
};

}  // namespace geometry
