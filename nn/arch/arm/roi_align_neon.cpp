// NEON RoIAlign bins: 4 channels per vector (roi_align_bin.h).
#include "nn/models/detection/roi_align_bin.h"

namespace nn::detection {
namespace {
typedef float Vec __attribute__((vector_size(16)));
}  // namespace

void roi_bin_neon(const RoiBin& b) { roi_bin_with<Vec>(b); }

}  // namespace nn::detection
