#include "apps/shle/frame_loader.h"

#include "apps/common/image_io.h"
#include "shle/disparity_io.h"
#include "shle/error.h"

namespace shleapp {

shle::RgbImage PngFrameLoader::load_image(const std::string& path) {
  imageio::Image img = imageio::load(path, 3, false, limits_);
  shle::RgbImage out;
  out.width = img.width;
  out.height = img.height;
  out.rgb = std::move(img.u8);
  return out;
}

bool PngFrameLoader::image_size(const std::string& path, int* width, int* height) {
  try {
    imageio::ImageInfo info = imageio::probe(path);  // no pixels decoded: no limit to apply
    *width = info.width;
    *height = info.height;
    return true;
  } catch (const std::exception&) {
    return false;
  }
}

shle::DisparityMap PngFrameLoader::load_png_disparity(const std::string& path, double scale) {
  imageio::ImageInfo info = imageio::probe(path);
  if (info.format != "PNG" || info.bit_depth != 16 || info.channels != 1)
    throw shle::Error(path + ": disparity PNG must be 16-bit single-channel, got " +
                      (info.format == "PNG" ? "" : "a " + info.format + " file, ") + std::to_string(info.bit_depth) +
                      "-bit with " + std::to_string(info.channels) + " channel(s)");
  imageio::check_limits(info, path, limits_);
  imageio::Image img = imageio::load(path, 0, true, limits_);
  if (img.bit_depth != 16 || img.channels != 1)
    throw shle::Error(path + ": disparity PNG must be 16-bit single-channel, got " + std::to_string(img.bit_depth) +
                      "-bit with " + std::to_string(img.channels) + " channel(s)");
  return shle::disparity_from_u16(img.u16.data(), img.width, img.height, scale, path);
}

}  // namespace shleapp
