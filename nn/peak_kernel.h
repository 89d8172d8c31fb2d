// The FMA-throughput loops behind nn::peak_gflops() (nn/peak.h), one per ISA
// (nn/kernel_table.h): `iterations` rounds of register-only multiply-adds; each returns
// the floating-point operations it did and adds its result to *sink. Declarations only.
#pragma once

namespace nn {

double peak_fma_scalar(long iterations, float* sink);
double peak_fma_avx2(long iterations, float* sink);
double peak_fma_avx512(long iterations, float* sink);
double peak_fma_neon(long iterations, float* sink);

}  // namespace nn
