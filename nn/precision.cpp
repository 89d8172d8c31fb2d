#include "nn/precision.h"

namespace nn {

const char* precision_name(Precision p) { return p == Precision::Bf16 ? "bf16" : "f32"; }

bool parse_precision(const std::string& text, Precision* out) {
  if (text == "f32" || text == "fp32") {
    *out = Precision::F32;
    return true;
  }
  if (text == "bf16") {
    *out = Precision::Bf16;
    return true;
  }
  return false;
}

}  // namespace nn
