#include "apps/common/exec_env.h"

#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "nn/isa.h"
#include "nn/winograd.h"

namespace apps {

void apply_exec_environment(const char* prog) {
  if (const char* text = std::getenv("NN_ISA"); text && *text) {
    nn::Isa isa;
    if (nn::parse_isa(text, &isa))
      nn::set_isa(isa);
    else
      std::fprintf(stderr, "%s: warning: NN_ISA is not one of scalar, avx2, avx512, neon; ignored\n", prog);
  }
  if (const char* text = std::getenv("NN_WINOGRAD"); text && std::strcmp(text, "0") == 0) nn::set_winograd(false);
}

}  // namespace apps
