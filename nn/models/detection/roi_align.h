// torchvision.ops.roi_align on one NHWC feature map (CPU kernel semantics): each RoI
// becomes out_h x out_w bins, each the mean of grid x grid bilinear samples.
// aligned=false: no half-pixel shift and RoI sides forced to at least 1 cell;
// aligned=true (detectron2's ROIAlignV2): coordinates shifted by -0.5, sides as they are.
// Samples beyond one cell outside the map count as zeros in the mean.
#pragma once

#include <cstddef>

#include "nn/models/detection/box_ops.h"
#include "nn/models/detection/roi_align_kernel.h"
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
// samples: room for one bin's samples (planned with roi_align_max_samples), or null;
// a bin needing more than sample_room samples (or than 16 without room) uses the heap.
void roi_align_one(const ConstTensorView& feature, int n, const Box& roi, const RoiAlignParams& p,
                   float* out, RoiSample* samples = nullptr, std::size_t sample_room = 0);

// The most samples one bin takes for an RoI whose sides on the map (box * scale) are
// at most max_roi_h x max_roi_w: sampling_ratio^2, or with adaptive sampling
// ceil(side / bins) per axis (plus one against rounding).
std::size_t roi_align_max_samples(const RoiAlignParams& p, float max_roi_h, float max_roi_w);

}  // namespace nn::detection
