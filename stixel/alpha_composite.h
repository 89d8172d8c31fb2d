// PIL's ImagingAlphaComposite of a source pixel with alpha `a` (0..255) over an
// opaque destination: 7 extra bits of precision, rounded division by 255. Shared
// by the overlay and the fitted bird's-eye view, which mimic Pillow's drawing.
#pragma once

#include <cstdint>

namespace stixel {

struct PilComposite {
  std::uint32_t coef1 = 0, coef2 = 0;
  explicit PilComposite(std::uint32_t a) {
    const std::uint32_t outa255 = a * 255 + 255 * (255 - a);
    coef1 = a * 255 * 255 * (1u << 7) / outa255;
    coef2 = 255 * (1u << 7) - coef1;
  }
  std::uint8_t operator()(std::uint32_t src, std::uint32_t dst) const {
    const std::uint32_t t = src * coef1 + dst * coef2 + (0x80u << 7);
    return static_cast<std::uint8_t>((((t >> 8) + t) >> 8) >> 7);
  }
};

}  // namespace stixel
