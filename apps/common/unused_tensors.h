// Tensors a weights file holds but the model does not read are reported, never
// silently dropped (e.g. torchvision's classifier.* next to the features).
#pragma once

#include <string>
#include <vector>

#include "weights/safetensors.h"

namespace apps {

// Prints "prog: warning: FILE: N tensors not used by WHAT: a, b, ..." when there are any.
void warn_unused_tensors(const char* prog, const weights::SafeTensors& st, const std::vector<std::string>& used,
                         const std::string& what);

}  // namespace apps
