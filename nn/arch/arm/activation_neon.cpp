// NEON activation kernel (nn/activation_kernel.h): full vectors from x, and the last
// count % 4 elements through a 4-float copy, so a tail gets the bits the same value would
// get inside a full vector and nothing past the end is read or written.
#include <cstddef>
#include <cstring>

#include "nn/activation_kernel.h"

#include "nn/arch/arm/vecmath_neon.h"

namespace nn {
namespace {

template <Act ACT>
void act_loop(float* x, std::size_t count) {
  std::size_t i = 0;
  for (; i + 8 <= count; i += 8) {
    vst1q_f32(x + i, vq_act<ACT>(vld1q_f32(x + i)));
    vst1q_f32(x + i + 4, vq_act<ACT>(vld1q_f32(x + i + 4)));
  }
  for (; i + 4 <= count; i += 4) vst1q_f32(x + i, vq_act<ACT>(vld1q_f32(x + i)));
  if (i < count) {
    const std::size_t left = count - i;
    float tail[4] = {0.0f, 0.0f, 0.0f, 0.0f};
    std::memcpy(tail, x + i, left * sizeof(float));
    vst1q_f32(tail, vq_act<ACT>(vld1q_f32(tail)));
    std::memcpy(x + i, tail, left * sizeof(float));
  }
}

}  // namespace

void apply_act_neon(int act, float* x, std::size_t count) {
  switch (static_cast<Act>(act)) {
    case Act::None: return;
    case Act::Relu: return act_loop<Act::Relu>(x, count);
    case Act::Gelu: return act_loop<Act::Gelu>(x, count);
    case Act::HardSwish: return act_loop<Act::HardSwish>(x, count);
    case Act::HardSigmoid: return act_loop<Act::HardSigmoid>(x, count);
    case Act::Sigmoid: return act_loop<Act::Sigmoid>(x, count);
  }
}

}  // namespace nn
