// Activations that kernels can apply in their epilogue.
#pragma once

namespace nn {

enum class Act {
  None,
  Relu,
  Gelu,       // exact: 0.5 x (1 + erf(x / sqrt 2)), PyTorch's nn.GELU() default
  HardSwish,  // x * relu6(x + 3) / 6
  HardSigmoid,// relu6(x + 3) / 6
  Sigmoid,
};

}  // namespace nn
