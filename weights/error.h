// The error the weights library throws. Messages are one line: "<file>: <problem>",
// e.g. "w.safetensors: missing tensor 'stem.weight' (expected shape [96, 3, 4, 4])".
#pragma once

#include <stdexcept>
#include <string>

namespace weights {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& what) : std::runtime_error(what) {}
};

}  // namespace weights
