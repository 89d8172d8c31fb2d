#include <cstddef>

#include "nn/activation_kernel.h"

#include "nn/arch/x86/vecmath_avx512.h"

namespace nn {
namespace {

template <Act ACT>
void act_loop(float* x, std::size_t count) {
  std::size_t i = 0;
  for (; i + 32 <= count; i += 32) {
    _mm512_storeu_ps(x + i, v512_act<ACT>(_mm512_loadu_ps(x + i)));
    _mm512_storeu_ps(x + i + 16, v512_act<ACT>(_mm512_loadu_ps(x + i + 16)));
  }
  for (; i < count; i += 16) {
    const std::size_t left = count - i;
    const __mmask16 m = left >= 16 ? __mmask16(0xFFFF) : __mmask16((1u << left) - 1);
    _mm512_mask_storeu_ps(x + i, m, v512_act<ACT>(_mm512_maskz_loadu_ps(m, x + i)));
  }
}

}  // namespace

void apply_act_avx512(int act, float* x, std::size_t count) {
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
