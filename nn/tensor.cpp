#include "nn/tensor.h"

namespace nn {

std::string shape_str(const Shape& s) {
  return "[" + std::to_string(s.n) + "," + std::to_string(s.h) + "," + std::to_string(s.w) + "," +
         std::to_string(s.c) + "]";
}

}  // namespace nn
