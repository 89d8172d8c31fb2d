#include "nn/activation.h"

#include <cmath>

#include "nn/isa.h"
#include "nn/kernel_table.h"

namespace nn {


float act_ref(Act act, float x) {
  switch (act) {
    case Act::None:
      return x;
    case Act::Relu:
      return x < 0.0f ? 0.0f : x;  // keeps NaN and -0, like torch.relu
    case Act::Gelu: {
      const double xd = x;
      return static_cast<float>(0.5 * xd * (1.0 + std::erf(xd * 0.70710678118654752440)));
    }
    case Act::HardSwish: {
      // PyTorch's float arithmetic, operation for operation (max/min keep NaN).
      float t = x + 3.0f;
      t = t < 0.0f ? 0.0f : t;
      t = t > 6.0f ? 6.0f : t;
      return x * t / 6.0f;
    }
    case Act::HardSigmoid: {
      float t = x + 3.0f;
      t = t < 0.0f ? 0.0f : t;
      t = t > 6.0f ? 6.0f : t;
      return t / 6.0f;
    }
    case Act::Sigmoid:
      return static_cast<float>(1.0 / (1.0 + std::exp(-static_cast<double>(x))));
  }
  return x;
}

void apply_act_ref(Act act, float* x, std::size_t count) {
  if (act == Act::None) return;
  for (std::size_t i = 0; i < count; ++i) x[i] = act_ref(act, x[i]);
}

void apply_act(Act act, float* x, std::size_t count) { apply_act(act, x, count, active_isa()); }

void apply_act(Act act, float* x, std::size_t count, Isa isa) {
  if (act == Act::None || count == 0) return;
  kernel_table(isa).apply_act(static_cast<int>(act), x, count);
}

void apply_act_scalar(int act, float* x, std::size_t count) { apply_act_ref(static_cast<Act>(act), x, count); }

}  // namespace nn
