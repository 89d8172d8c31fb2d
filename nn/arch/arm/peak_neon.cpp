// The NEON FMA-throughput loop (nn/peak_loop.h): 12 q-register chains. A Cortex-A76 /
// Neoverse-N1-class core has 2 FMA pipes with 4-cycle latency, so at least 8 chains keep
// both busy; 12 leaves headroom for wider cores (Neoverse V1/V2: 4 pipes) without spilling.
#include <arm_neon.h>

#include "nn/peak_kernel.h"
#include "nn/peak_loop.h"

namespace nn {
namespace {
struct FmaNeon {
  // acc + mul * add: the accumulator is fmla's destination, so no register copies.
  static float32x4_t step(float32x4_t acc, float32x4_t mul, float32x4_t add) { return vfmaq_f32(acc, mul, add); }
};
}  // namespace

double peak_fma_neon(long iterations, float* sink) { return peak_loop_with<float32x4_t, 12, FmaNeon>(iterations, sink); }

}  // namespace nn
