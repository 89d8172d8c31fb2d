// What the scalar path can reach (nn/peak_loop.h): the baseline vector unit (SSE2 on
// x86-64, Advanced SIMD on aarch64) doing a multiply and an add per lane (no FMA: the scalar
// kernels do not contract), 12 chains of 4 lanes.
#include "nn/peak_kernel.h"
#include "nn/peak_loop.h"

namespace nn {
namespace {
typedef float Vec4 __attribute__((vector_size(16)));
struct MulAdd {
  static Vec4 step(Vec4 acc, Vec4 mul, Vec4 add) { return acc * mul + add; }
};
}  // namespace

double peak_fma_scalar(long iterations, float* sink) { return peak_loop_with<Vec4, 12, MulAdd>(iterations, sink); }

}  // namespace nn
