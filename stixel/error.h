// Errors of the stixel library: one line naming the input (file, tensor, option)
// and the problem. Apps print them as "prog: message" and exit non-zero.
#pragma once

#include <stdexcept>
#include <string>

namespace stixel {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& what) : std::runtime_error(what) {}
};

}  // namespace stixel
