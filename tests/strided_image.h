// Interleaved RGB8 pixels with `pad` bytes of seeded garbage after every row: the
// strided-buffer tests check that padding is never read.
#pragma once

#include <cstdint>
#include <cstring>
#include <vector>

#include "nn/models/synthetic_weights.h"

namespace testutil {

inline std::vector<std::uint8_t> with_padding(const std::vector<std::uint8_t>& px, int w, int h, std::size_t pad) {
  const std::size_t row = static_cast<std::size_t>(w) * 3, stride = row + pad;
  std::vector<std::uint8_t> out(stride * h);
  nn::SplitMix64 rng(11);
  for (auto& b : out) b = static_cast<std::uint8_t>(rng.next());
  for (int r = 0; r < h; ++r) std::memcpy(out.data() + r * stride, px.data() + r * row, row);
  return out;
}

}  // namespace testutil
