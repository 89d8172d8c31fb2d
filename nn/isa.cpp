#include "nn/isa.h"

#include <cstring>

#include "nn/exec.h"

namespace nn {

ExecOptions& mutable_exec();  // nn/exec.cpp

const char* isa_name(Isa isa) {
  switch (isa) {
    case Isa::Scalar: return "scalar";
    case Isa::Avx2: return "avx2";
    case Isa::Avx512: return "avx512";
  }
  return "unknown";
}

bool parse_isa(const char* text, Isa* out) {
  if (!text) return false;
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

bool detect_avx512_bf16() {
  static const bool cached = [] {
    __builtin_cpu_init();
    return detect_isa() == Isa::Avx512 && __builtin_cpu_supports("avx512bf16");
  }();
  return cached;
}

Isa active_isa() { return min_isa(detect_isa(), current_exec().max_isa); }

void set_isa(Isa isa) { mutable_exec().max_isa = min_isa(isa, detect_isa()); }

}  // namespace nn
