// Image decoding for the SHLE pipeline (libpng/libjpeg via apps/common/image_io): the left
// images as RGB, their size from the file header, and 16-bit PNG disparity. Every file
// is held to the pixel limit (shle --max-pixels) before it is decoded.
#pragma once

#include <string>

#include "apps/common/image_io.h"
#include "shle/pipeline.h"

namespace shleapp {

class PngFrameLoader : public shle::FrameLoader {
 public:
  explicit PngFrameLoader(imageio::DecodeLimits limits = {}) : limits_(limits) {}
  shle::RgbImage load_image(const std::string& path) override;
  // Reads only the file header (imageio::probe); false when it cannot be read. The
  // pixel limit applies where pixels are decoded (load_image, load_png_disparity).
  bool image_size(const std::string& path, int* width, int* height) override;
  // Checks from the header that the file is a 16-bit gray PNG within the limit, then decodes.
  shle::DisparityMap load_png_disparity(const std::string& path, double scale) override;

 private:
  imageio::DecodeLimits limits_;
};

}  // namespace shleapp
