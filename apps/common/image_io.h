// Image files for the apps (stb_image / stb_image_write); the runtime libraries
// never touch image files. Errors are json-free one-liners naming the path.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace imageio {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& what) : std::runtime_error(what) {}
};

struct Image {
  int width = 0, height = 0, channels = 0;  // channels: 1 gray, 3 RGB, 4 RGBA
  int bit_depth = 8;                        // 8 or 16
  std::vector<std::uint8_t> u8;             // bit_depth 8: row-major, interleaved
  std::vector<std::uint16_t> u16;           // bit_depth 16 (e.g. disparity PNGs)
};

// Loads PNG/JPEG/BMP. want_channels: 0 = as stored, else converted to 1/3/4.
// keep_16bit: keep 16-bit PNG samples in u16 instead of reducing to 8 bits.
Image load(const std::string& path, int want_channels = 0, bool keep_16bit = false);

// Encodes 8-bit interleaved pixels as PNG bytes.
std::vector<std::uint8_t> encode_png(const std::uint8_t* pixels, int width, int height,
                                     int channels);

// Writes a PNG atomically (outputs::write_file: temporary file, then rename); never
// leaves a partial file. Sets of files: encode_png and outputs::FileSet.
void save_png(const std::string& path, const std::uint8_t* pixels, int width, int height,
              int channels);

}  // namespace imageio
