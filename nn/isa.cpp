#include "nn/isa.h"

#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace nn {
namespace {

Isa g_override = Isa::Avx512;
bool g_has_override = false;

Isa env_isa() {
  static const Isa cached = [] {
    const char* text = std::getenv("NN_ISA");
    Isa isa = Isa::Avx512;
    if (text && *text && !parse_isa(text, &isa)) {
      std::fprintf(stderr, "warning: NN_ISA=%s is not one of scalar, avx2, avx512; ignored\n", text);
      isa = Isa::Avx512;
    }
    return isa;
  }();
  return cached;
}

Isa min_isa(Isa a, Isa b) { return static_cast<int>(a) < static_cast<int>(b) ? a : b; }

}  // namespace

const char* isa_name(Isa isa) {
  switch (isa) {
    case Isa::Scalar: return "scalar";
    case Isa::Avx2: return "avx2";
    case Isa::Avx512: return "avx512";
  }
  return "unknown";
}

bool parse_isa(const char* text, Isa* out) {
  if (std::strcmp(text, "scalar") == 0) { *out = Isa::Scalar; return true; }
  if (std::strcmp(text, "avx2") == 0) { *out = Isa::Avx2; return true; }
  if (std::strcmp(text, "avx512") == 0) { *out = Isa::Avx512; return true; }
  return false;
}

Isa detect_isa() {
  static const Isa cached = [] {
    __builtin_cpu_init();
    // libgcc's checks include the OS having enabled the register state (XCR0).
    if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") &&
        __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512vl") &&
        __builtin_cpu_supports("fma"))
      return Isa::Avx512;
    if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") &&
        __builtin_cpu_supports("f16c"))
      return Isa::Avx2;
    return Isa::Scalar;
  }();
  return cached;
}

Isa active_isa() {
  Isa isa = min_isa(detect_isa(), env_isa());
  if (g_has_override) isa = min_isa(isa, g_override);
  return isa;
}

void set_isa(Isa isa) {
  g_override = min_isa(isa, detect_isa());
  g_has_override = true;
}

}  // namespace nn
