// torchvision.ops.roi_align on one NHWC feature map (CPU kernel semantics): each RoI
// becomes out_h x out_w bins, each the mean of grid x grid bilinear samples.
// aligned=false: no half-pixel shift and RoI sides forced to at least 1 cell.
// Samples beyond one cell outside the map count as zeros in the mean.
#pragma once

#include "nn/models/detection/box_ops.h"
#include "nn/isa.h"
#include "nn/tensor.h"

namespace nn::detection {

struct RoiAlignParams {
  int out_h = 7, out_w = 7;
  float spatial_scale = 1.0f;
  int sampling_ratio = 2;  // <= 0: adaptive, ceil(roi side / bins)
  bool aligned = false;
  // The bin kernel; set where the parameters are made, outside any parallel region.
  Isa isa = active_isa();
};

// feature: image n of an NHWC map; out: out_h * out_w * C floats in (y, x, c) order.
void roi_align_one(const ConstTensorView& feature, int n, const Box& roi, const RoiAlignParams& p,
                   float* out);

}  // namespace nn::detection
