// Size of an embedded PNG/JPEG read from its header alone (no pixel decoding:
// the library never decodes images; the apps do).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace stixel {

enum class ImageFormat { None, Png, Jpeg, Unknown };

// By magic: PNG 89 50 4E 47 0D 0A 1A 0A, JPEG FF D8 FF; None for no bytes.
ImageFormat image_format(const std::uint8_t* data, std::size_t size);

// Width/height from the PNG IHDR or the first JPEG SOFn segment. Returns false
// (and leaves width/height alone) if the header is missing or malformed.
bool image_size(const std::uint8_t* data, std::size_t size, int* width, int* height);

}  // namespace stixel
