// detectron2's inference input path for an RGB8 image: ResizeShortestEdge's size rule
// (short side 800, long side at most 1333, rounded half up), Pillow's uint8 bilinear
// resize, RGB -> BGR, (x - pixel_mean) / pixel_std in float32, zero padding bottom
// and right to a multiple of 32 (after normalising, so the padding is the mean colour).
#pragma once

#include <cstdint>
#include <vector>

#include "nn/models/detection/pillow_resize.h"
#include "nn/models/detection/transform.h"
#include "nn/tensor.h"

namespace nn::detection {

struct Detectron2TransformConfig {
  int min_size = 800, max_size = 1333;            // INPUT.MIN_SIZE_TEST / MAX_SIZE_TEST
  float mean[3] = {103.530f, 116.280f, 123.675f};  // MODEL.PIXEL_MEAN, B, G, R
  float std[3] = {1.0f, 1.0f, 1.0f};               // MODEL.PIXEL_STD
  int size_divisible = 32;
};

// ResizeShortestEdge.get_output_shape in double: s = min_size / short side, the long
// side capped at max_size, each side int(x + 0.5). Throws nn::Error below 32 px or
// above 20000 px.
ImageSizes detectron2_sizes(int h, int w, const Detectron2TransformConfig& cfg);

class Detectron2Transform {
 public:
  void plan(const ImageSizes& sizes);
  // rgb: orig_h x orig_w x 3 RGB8. out: {1, padded_h, padded_w, 3}, BGR normalised.
  void run(const std::uint8_t* rgb, const Detectron2TransformConfig& cfg, const TensorView& out);
  // The resized RGB8 image of the last run (resized_h x resized_w x 3).
  const std::vector<std::uint8_t>& resized() const { return resized_; }

 private:
  ImageSizes sizes_;
  PillowResize resize_;
  std::vector<std::uint8_t> resized_;
};

}  // namespace nn::detection
