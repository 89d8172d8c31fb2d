// Image decoding for the SHLE pipeline (libpng/libjpeg via apps/common/image_io): the left
// images as RGB, their size from the PNG header, and 16-bit PNG disparity.
#pragma once

#include <string>

#include "shle/pipeline.h"

namespace shleapp {

class PngFrameLoader : public shle::FrameLoader {
 public:
  shle::RgbImage load_image(const std::string& path) override;
  // Reads only the PNG signature and IHDR chunk; other formats are decoded.
  bool image_size(const std::string& path, int* width, int* height) override;
  shle::DisparityMap load_png_disparity(const std::string& path, double scale) override;
};

}  // namespace shleapp
