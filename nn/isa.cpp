#include "nn/isa.h"

#include <cstring>
#include <initializer_list>

#include "nn/cpu_features.h"
#include "nn/exec.h"

namespace nn {

ExecOptions& mutable_exec();  // nn/exec.cpp

const char* isa_name(Isa isa) {
  switch (isa) {
    case Isa::Scalar: return "scalar";
    case Isa::Avx2: return "avx2";
    case Isa::Avx512: return "avx512";
    case Isa::Neon: return "neon";
  }
  return "unknown";
}

int isa_level(Isa isa) {
  switch (isa) {
    case Isa::Scalar: return 0;
    case Isa::Avx2: return 1;
    case Isa::Neon: return 1;
    case Isa::Avx512: return 2;
  }
  return 0;
}

bool parse_isa(const char* text, Isa* out) {
  if (!text) return false;
  for (Isa isa : {Isa::Scalar, Isa::Avx2, Isa::Avx512, Isa::Neon}) {
    if (std::strcmp(text, isa_name(isa)) == 0) {
      *out = isa;
      return true;
    }
  }
  return false;
}

bool isa_supported(Isa isa) {
  const CpuFeatures& f = cpu_features();
  switch (isa) {
    case Isa::Scalar: return true;
#if defined(__x86_64__)
    case Isa::Avx2: return f.avx2 && f.fma && f.f16c;
    case Isa::Avx512: return f.avx512f && f.avx512bw && f.avx512dq && f.avx512vl && f.fma && f.avx2 && f.f16c;
#endif
#if defined(__aarch64__)
    case Isa::Neon: return f.neon;
#endif
    default: return false;
  }
}

Isa detect_isa() {
  static const Isa cached = [] {
    Isa best = Isa::Scalar;
    for (Isa isa : {Isa::Avx2, Isa::Avx512, Isa::Neon})
      if (isa_supported(isa) && isa_level(isa) > isa_level(best)) best = isa;
    return best;
  }();
  return cached;
}

Isa cap_isa(Isa cap) {
  if (isa_supported(cap)) return cap;
  Isa best = Isa::Scalar;
  for (Isa isa : {Isa::Avx2, Isa::Avx512, Isa::Neon})
    if (isa_supported(isa) && isa_level(isa) <= isa_level(cap) && isa_level(isa) > isa_level(best)) best = isa;
  return best;
}

Isa active_isa() { return cap_isa(current_exec().max_isa); }

void set_isa(Isa isa) { mutable_exec().max_isa = cap_isa(isa); }

}  // namespace nn
