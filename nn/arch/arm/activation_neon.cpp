// NEON activation kernel: 4 floats per q register (nn/activation_loop.h).
#include "nn/activation_kernel.h"
#include "nn/activation_loop.h"
#include "nn/arch/arm/vecmath_neon.h"

namespace nn {
namespace {
struct ActOpsNeon {
  using V = float32x4_t;
  static constexpr int kLanes = 4;
  static V loadu(const float* p) { return vld1q_f32(p); }
  static void storeu(float* p, V v) { vst1q_f32(p, v); }
  template <Act ACT>
  static V act(V v) { return vq_act<ACT>(v); }
};
}  // namespace

void apply_act_neon(int act, float* x, std::size_t count) { apply_act_with<ActOpsNeon>(act, x, count); }

}  // namespace nn
