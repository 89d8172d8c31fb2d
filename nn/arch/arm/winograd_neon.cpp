// NEON Winograd F(4x4, 3x3) transforms: 4 channels per vector (nn/winograd_transform.h).
#include "nn/winograd_transform.h"

namespace nn {
namespace {
typedef float Vec __attribute__((vector_size(16)));
}  // namespace

void winograd_input_tile_neon(const WinogradInputTile& t) { winograd_tile_with<Vec>(t); }
void winograd_output_tile_neon(const WinogradOutputTile& t) { winograd_tile_with<Vec>(t); }

}  // namespace nn
