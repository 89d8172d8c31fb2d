// AVX512 RoIAlign bins: 16 channels per vector (roi_align_bin.h).
#include "nn/models/detection/roi_align_bin.h"

namespace nn::detection {
namespace {
typedef float Vec __attribute__((vector_size(64)));
}  // namespace

void roi_bin_avx512(const RoiBin& b) { roi_bin_with<Vec>(b); }

}  // namespace nn::detection
