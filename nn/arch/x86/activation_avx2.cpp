#include <cstddef>

#include "nn/activation_kernel.h"

#include "nn/arch/x86/vecmath_avx2.h"

namespace nn {
namespace {

// Lane j is enabled when j < n (n in 0..8).
inline __m256i tail_mask(std::size_t n) {
  return _mm256_cmpgt_epi32(_mm256_set1_epi32(static_cast<int>(n)),
                            _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
}

template <Act ACT>
void act_loop(float* x, std::size_t count) {
  std::size_t i = 0;
  for (; i + 16 <= count; i += 16) {
    _mm256_storeu_ps(x + i, v256_act<ACT>(_mm256_loadu_ps(x + i)));
    _mm256_storeu_ps(x + i + 8, v256_act<ACT>(_mm256_loadu_ps(x + i + 8)));
  }
  for (; i < count; i += 8) {
    const std::size_t left = count - i;
    if (left >= 8) {
      _mm256_storeu_ps(x + i, v256_act<ACT>(_mm256_loadu_ps(x + i)));
      continue;
    }
    const __m256i m = tail_mask(left);
    _mm256_maskstore_ps(x + i, m, v256_act<ACT>(_mm256_maskload_ps(x + i, m)));
  }
}

}  // namespace

void apply_act_avx2(int act, float* x, std::size_t count) {
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
