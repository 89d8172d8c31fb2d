// Run-time instruction-set selection. One binary carries scalar, AVX2+FMA and
// AVX-512 kernels; a model uses the best one the CPU (and the OS) supports, capped by
// its options (nn/exec.h: ExecOptions::max_isa), so the scalar and AVX2 paths stay
// usable and testable on an AVX-512 machine.
#pragma once

namespace nn {

enum class Isa { Scalar = 0, Avx2 = 1, Avx512 = 2 };

const char* isa_name(Isa isa);
// What the hardware supports (probed once; immutable afterwards).
Isa detect_isa();
// Whether the CPU also has AVX512_BF16 (probed once).
bool detect_avx512_bf16();
// min(detect_isa(), the calling thread's ExecOptions::max_isa): what code running on
// this thread outside a parallel region picks. Kernels called inside parallel regions
// take their ISA as an argument instead (worker threads do not see the caller's scope).
Isa active_isa();
// Sets the calling thread's max_isa (clamped to what the CPU supports), for the rest
// of its current ExecScope; our tests and apps use it to run every path.
void set_isa(Isa isa);
// Parses "scalar", "avx2", "avx512"; returns false on anything else.
bool parse_isa(const char* text, Isa* out);
inline Isa min_isa(Isa a, Isa b) { return static_cast<int>(a) < static_cast<int>(b) ? a : b; }

}  // namespace nn
