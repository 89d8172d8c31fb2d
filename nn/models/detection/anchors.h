// torchvision's AnchorGenerator: rounded cell anchors per level (ratio-major, then
// size), shifted by whole strides (no half-stride offset), ordered level, row,
// column, anchor.
#pragma once

#include <vector>

#include "nn/models/detection/box_ops.h"

namespace nn::detection {

// The cell anchors [-w/2, -h/2, w/2, h/2], rounded half-to-even, of one level.
std::vector<Box> cell_anchors(const std::vector<float>& sizes, const std::vector<float>& aspect_ratios);

// detectron2's DefaultAnchorGenerator.generate_cell_anchors: size-major, then ratio;
// w = sqrt(size^2 / ratio), h = ratio * w in double, not rounded, then float32.
std::vector<Box> cell_anchors_unrounded(const std::vector<float>& sizes, const std::vector<float>& aspect_ratios);

// Anchors of one level for a grid_h x grid_w map of a padded_h x padded_w image;
// the stride is the integer quotient of the padded size by the grid size.
std::vector<Box> grid_anchors(const std::vector<Box>& cell, int grid_h, int grid_w, int padded_h, int padded_w);
// The same with given strides (detectron2: the feature strides 4..64, offset 0).
std::vector<Box> grid_anchors_strided(const std::vector<Box>& cell, int grid_h, int grid_w, int stride_h,
                                      int stride_w);

}  // namespace nn::detection
