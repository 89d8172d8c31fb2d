// AVX2 activation kernel: 8 floats per ymm (nn/activation_loop.h).
#include "nn/activation_kernel.h"
#include "nn/activation_loop.h"
#include "nn/arch/x86/vecmath_avx2.h"

namespace nn {
namespace {
struct ActOpsAvx2 {
  using V = __m256;
  static constexpr int kLanes = 8;
  static V loadu(const float* p) { return _mm256_loadu_ps(p); }
  static void storeu(float* p, V v) { _mm256_storeu_ps(p, v); }
  template <Act ACT>
  static V act(V v) { return v256_act<ACT>(v); }
};
}  // namespace

void apply_act_avx2(int act, float* x, std::size_t count) { apply_act_with<ActOpsAvx2>(act, x, count); }

}  // namespace nn
