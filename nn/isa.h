// Run-time instruction-set selection. One binary carries scalar, AVX2+FMA and
// AVX-512 kernels; the best one the CPU (and the OS) supports is used unless the
// environment variable NN_ISA=scalar|avx2|avx512 asks for a lower one, so the
// scalar and AVX2 paths stay testable on an AVX-512 machine.
#pragma once

namespace nn {

enum class Isa { Scalar = 0, Avx2 = 1, Avx512 = 2 };

const char* isa_name(Isa isa);
// What the hardware supports, ignoring NN_ISA.
Isa detect_isa();
// What kernels use: min(detect_isa(), NN_ISA, set_isa override). Cached.
Isa active_isa();
// Overrides the active ISA for this process (clamped to what the CPU supports);
// tests use it to run every path. Not thread-safe against concurrent forwards.
void set_isa(Isa isa);
// Parses "scalar", "avx2", "avx512"; returns false on anything else.
bool parse_isa(const char* text, Isa* out);

}  // namespace nn
