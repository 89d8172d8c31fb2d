#include "stixel/image_header.h"

#include <cstring>

namespace stixel {

ImageFormat image_format(const std::uint8_t* p, std::size_t n) {
  static const std::uint8_t png[8] = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
  if (n == 0) return ImageFormat::None;
  if (n >= 8 && std::memcmp(p, png, 8) == 0) return ImageFormat::Png;
  if (n >= 3 && p[0] == 0xFF && p[1] == 0xD8 && p[2] == 0xFF) return ImageFormat::Jpeg;
  return ImageFormat::Unknown;
}

bool image_size(const std::uint8_t* p, std::size_t n, int* width, int* height) {
  auto be16 = [&](std::size_t i) { return (p[i] << 8) | p[i + 1]; };
  auto be32 = [&](std::size_t i) {
    return (std::uint32_t(p[i]) << 24) | (std::uint32_t(p[i + 1]) << 16) |
           (std::uint32_t(p[i + 2]) << 8) | std::uint32_t(p[i + 3]);
  };
  switch (image_format(p, n)) {
    case ImageFormat::Png: {
      // Signature, then the IHDR chunk: length 13, "IHDR", width, height.
      if (n < 24 || std::memcmp(p + 12, "IHDR", 4) != 0) return false;
      const std::uint32_t w = be32(16), h = be32(20);
      if (w == 0 || h == 0 || w > 0x7FFFFFFF || h > 0x7FFFFFFF) return false;
      *width = static_cast<int>(w);
      *height = static_cast<int>(h);
      return true;
    }
    case ImageFormat::Jpeg: {
      std::size_t i = 2;
      while (i + 4 <= n) {
        if (p[i] != 0xFF) return false;
        const std::uint8_t m = p[i + 1];
        if (m == 0xFF) {  // fill byte
          ++i;
          continue;
        }
        if (m == 0xD8 || m == 0x01 || (m >= 0xD0 && m <= 0xD7)) {
          i += 2;
          continue;
        }
        if (m == 0xD9 || m == 0xDA) return false;  // no frame header before the scan
        const std::size_t len = be16(i + 2);
        if (len < 2 || i + 2 + len > n) return false;
        // SOF0..SOF15 except DHT (C4), JPG (C8) and DAC (CC).
        if (m >= 0xC0 && m <= 0xCF && m != 0xC4 && m != 0xC8 && m != 0xCC) {
          if (len < 7) return false;
          const int h = be16(i + 5), w = be16(i + 7);
          if (w == 0 || h == 0) return false;
          *width = w;
          *height = h;
          return true;
        }
        i += 2 + len;
      }
      return false;
    }
    default:
      return false;
  }
}

}  // namespace stixel
