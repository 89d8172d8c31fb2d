// Plain data shared by the SHLE stages: boxes, candidate detections and the pixel
// buffers the apps hand over (the library never decodes image files).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace shle {

// Axis-aligned box in pixels, corners (x0, y0) top-left and (x1, y1) bottom-right.
struct Box {
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  double width() const { return x1 - x0; }
  double height() const { return y1 - y0; }
  bool finite() const;
};

// One box proposed for a frame with its confidence (1 for annotations).
struct Candidate {
  Box box;
  double score = 1.0;
};

// Disparity in pixels, row-major. Values <= 0, NaN or infinite are invalid
// (no depth). Held as float: exact for the 1/32 px SmarterEye format.
struct DisparityMap {
  int width = 0, height = 0;
  std::vector<float> d;
  float at(int u, int v) const { return d[static_cast<std::size_t>(v) * width + u]; }
};

// 8-bit RGB, interleaved, rows of width * 3 bytes.
struct RgbImage {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;
};

// 8-bit single channel, rows of `width` bytes.
struct GrayImage {
  int width = 0, height = 0;
  std::vector<std::uint8_t> px;
};

// Read-only view of a single-channel image.
struct GrayView {
  int width = 0, height = 0;
  const std::uint8_t* data = nullptr;
};

inline GrayView view(const GrayImage& g) { return GrayView{g.width, g.height, g.px.data()}; }

// Luma with the ITU-R BT.601 integer weights (77 R + 150 G + 29 B + 128) >> 8.
// `rgb` must hold width * height * 3 bytes.
GrayImage to_gray(const RgbImage& rgb);
// The same into `out`, reusing its storage.
void to_gray(const RgbImage& rgb, GrayImage* out);

}  // namespace shle
