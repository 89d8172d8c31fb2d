// What the CPU (and the OS) offers, probed once. This is the only place in roadnn that
// asks the hardware: nn/isa.cpp turns it into the ISA levels and nn/kernel_table.cpp into
// the kernels; everything else asks those two, except shle/mil_haar.cpp, which mimics
// OpenCV's own dispatch (its integral image's rounding depends on OpenCV's vector width,
// whatever our kernel cap is).
#pragma once

namespace nn {

struct CpuFeatures {
  // x86-64 (libgcc's checks include the OS having enabled the register state, XCR0).
  bool avx2 = false, fma = false, f16c = false;
  bool avx512f = false, avx512bw = false, avx512dq = false, avx512vl = false, avx512cd = false;
  bool avx512_bf16 = false;
  // aarch64: Advanced SIMD is part of the base architecture; the rest from
  // getauxval(AT_HWCAP / AT_HWCAP2).
  bool neon = false, asimd_dotprod = false, bf16 = false;
};

const CpuFeatures& cpu_features();

}  // namespace nn
