// GeneralizedRCNNTransform at inference: normalise, resize with torchvision's size
// rule and bilinear arithmetic, zero-pad (in normalised space) bottom and right to a
// multiple of size_divisible.
#pragma once

#include "nn/tensor.h"

namespace nn::detection {

struct TransformConfig {
  int min_size = 800, max_size = 1333;
  float mean[3] = {0.485f, 0.456f, 0.406f};
  float std[3] = {0.229f, 0.224f, 0.225f};
  int size_divisible = 32;
};

struct ImageSizes {
  int orig_h = 0, orig_w = 0;
  int resized_h = 0, resized_w = 0;  // the "image_sizes" boxes are clipped to
  int padded_h = 0, padded_w = 0;    // the batched tensor the backbone sees
};

// An ImageSizes holding only the original size h x w, after checking it is one a
// detector takes (throws nn::Error below 32 px or above 20000 px).
ImageSizes checked_input_size(int h, int w);

// scale = min(min_size / short side, max_size / long side) in float32; output side =
// floor(side * scale) in double. Throws nn::Error below 32 px or on absurd sizes.
ImageSizes transform_sizes(int h, int w, const TransformConfig& cfg);

// image: [3, orig_h, orig_w] RGB in [0, 1] (one image of an NCHW batch).
// normalised: 3 * orig_h * orig_w floats; resized: 3 * resized_h * resized_w floats
// (scratch the caller plans once). out: {1, padded_h, padded_w, 3}.
void transform_image(const float* image, const ImageSizes& s, const TransformConfig& cfg, float* normalised,
                     float* resized, const TensorView& out);

}  // namespace nn::detection
