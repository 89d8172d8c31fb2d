// Run-time instruction-set selection. One binary carries the kernels of every ISA of
// its architecture (x86-64: scalar, AVX2+FMA, AVX-512; aarch64: scalar, NEON); a model
// uses the best one the CPU supports, capped by its options (nn/exec.h:
// ExecOptions::max_isa), so the lower paths stay usable and testable on any machine.
// The kernels of an ISA come from its table (nn/kernel_table.h).
#pragma once

namespace nn {

// Levels: scalar (0) < AVX2 = NEON (1) < AVX-512 (2). A cap of one architecture's ISA
// on the other means "at most that level": max_isa = avx2 on an ARM CPU runs NEON.
enum class Isa { Scalar = 0, Avx2 = 1, Avx512 = 2, Neon = 3 };

const char* isa_name(Isa isa);
// The level of an ISA (see above).
int isa_level(Isa isa);
// Whether this build and CPU can run the ISA's kernels.
bool isa_supported(Isa isa);
// The best ISA this build and CPU support (probed once; immutable afterwards).
Isa detect_isa();
// The best supported ISA whose level is at most cap's.
Isa cap_isa(Isa cap);
// cap_isa(the calling thread's ExecOptions::max_isa): what code running on this thread
// outside a parallel region picks. Kernels called inside parallel regions take their
// ISA as an argument instead (worker threads do not see the caller's scope).
Isa active_isa();
// Sets the calling thread's max_isa (capped to what the CPU supports), for the rest
// of its current ExecScope; our tests and apps use it to run every path.
void set_isa(Isa isa);
// Parses "scalar", "avx2", "avx512", "neon"; returns false on anything else.
bool parse_isa(const char* text, Isa* out);

}  // namespace nn
