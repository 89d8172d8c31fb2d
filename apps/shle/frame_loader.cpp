#include "apps/shle/frame_loader.h"

#include <cstdio>
#include <cstring>

#include "apps/common/image_io.h"
#include "shle/disparity_io.h"
#include "shle/error.h"

namespace shleapp {

shle::RgbImage PngFrameLoader::load_image(const std::string& path) {
  imageio::Image img = imageio::load(path, 3);
  shle::RgbImage out;
  out.width = img.width;
  out.height = img.height;
  out.rgb = std::move(img.u8);
  return out;
}

bool PngFrameLoader::image_size(const std::string& path, int* width, int* height) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return false;
  unsigned char b[24];
  std::size_t got = std::fread(b, 1, sizeof b, f);
  std::fclose(f);
  static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
  if (got == sizeof b && std::memcmp(b, sig, 8) == 0 && std::memcmp(b + 12, "IHDR", 4) == 0) {
    auto be32 = [](const unsigned char* p) {
      return (static_cast<unsigned long>(p[0]) << 24) | (static_cast<unsigned long>(p[1]) << 16) |
             (static_cast<unsigned long>(p[2]) << 8) | p[3];
    };
    unsigned long w = be32(b + 16), h = be32(b + 20);
    if (w == 0 || h == 0 || w > 65535 || h > 65535) return false;
    *width = static_cast<int>(w);
    *height = static_cast<int>(h);
    return true;
  }
  try {
    imageio::Image img = imageio::load(path, 1);
    *width = img.width;
    *height = img.height;
    return true;
  } catch (const std::exception&) {
    return false;
  }
}

shle::DisparityMap PngFrameLoader::load_png_disparity(const std::string& path, double scale) {
  imageio::Image img = imageio::load(path, 0, true);
  if (img.bit_depth != 16 || img.channels != 1)
    throw shle::Error(path + ": disparity PNG must be 16-bit single-channel, got " + std::to_string(img.bit_depth) +
                      "-bit with " + std::to_string(img.channels) + " channel(s)");
  return shle::disparity_from_u16(img.u16.data(), img.width, img.height, scale, path);
}

}  // namespace shleapp
