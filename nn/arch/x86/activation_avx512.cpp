// AVX-512 activation kernel: 16 floats per zmm (nn/activation_loop.h).
#include "nn/activation_kernel.h"
#include "nn/activation_loop.h"
#include "nn/arch/x86/vecmath_avx512.h"

namespace nn {
namespace {
struct ActOpsAvx512 {
  using V = __m512;
  static constexpr int kLanes = 16;
  static V loadu(const float* p) { return _mm512_loadu_ps(p); }
  static void storeu(float* p, V v) { _mm512_storeu_ps(p, v); }
  template <Act ACT>
  static V act(V v) { return v512_act<ACT>(v); }
};
}  // namespace

void apply_act_avx512(int act, float* x, std::size_t count) { apply_act_with<ActOpsAvx512>(act, x, count); }

}  // namespace nn
