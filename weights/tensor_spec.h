// What a model expects to find in its weights file (whisper.cpp style): each
// model lists its tensors and shapes, and loading checks the file against the
// list before any value is used.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "weights/safetensors.h"

namespace weights {

struct TensorSpec {
  std::string name;
  std::vector<std::int64_t> shape;
};

// Checks every spec in order: present, float dtype (F32/F16/BF16), exact shape,
// all values finite. Throws Error naming the file and the first problem, e.g.
//   "w.safetensors: missing tensor 'features.1.0.block.0.weight' (expected shape [96, 1, 7, 7])"
//   "w.safetensors: tensor 'features.0.0.weight' has shape [96, 3, 3, 3], expected [96, 3, 4, 4]"
//   "w.safetensors: tensor 'features.0.0.bias' contains NaN (element 17)"
// Returns the names in the file that no spec mentions, in file order, so the
// caller can warn about them (padding tensors are not listed).
std::vector<std::string> check_tensors(const SafeTensors& st, const std::vector<TensorSpec>& specs);

// Tensors the file holds that `used` does not name, described in one line
// ("FILE: N tensors not used by WHAT: a, b, ..." with at most 8 names, each quoted as
// in errors), or "" when every tensor is used. Reported, never silently dropped.
std::string unused_tensors_warning(const SafeTensors& st, const std::vector<std::string>& used,
                                   const std::string& what);

}  // namespace weights
