// x[pixel][c] *= scale[c] over an NHWC tensor: MobileNetV3's squeeze-excitation
// applying its per-channel gate. One multiply per element, so any split of the
// pixels over the team gives the same bits.
#pragma once

#include "nn/tensor.h"

namespace nn {

void scale_channels(const TensorView& x, const float* scale);

}  // namespace nn
