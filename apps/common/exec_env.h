// The environment conventions of our programs, turned into the main thread's engine
// options (the libraries never read the environment):
//   NN_ISA=scalar|avx2|avx512|neon   cap the kernel set (e.g. to run the AVX2 path on AVX-512)
//   NN_WINOGRAD=0                    pack 3x3 stride-1 convolutions for the direct form
// Command-line flags applied afterwards override them.
#pragma once

namespace apps {

// Applies NN_ISA / NN_WINOGRAD to the calling thread; a bad value is ignored with a
// one-line warning on stderr naming `prog`.
void apply_exec_environment(const char* prog);

}  // namespace apps
