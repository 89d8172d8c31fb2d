#include "apps/common/unused_tensors.h"

#include <cstdio>

#include "weights/tensor_spec.h"

namespace apps {

void warn_unused_tensors(const char* prog, const weights::SafeTensors& st, const std::vector<std::string>& used,
                         const std::string& what) {
  const std::string w = weights::unused_tensors_warning(st, used, what);
  if (!w.empty()) std::fprintf(stderr, "%s: warning: %s\n", prog, w.c_str());
}

}  // namespace apps
