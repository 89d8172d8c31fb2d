// Dense depth from stixels.
#pragma once

#include <cstdint>
#include <vector>

#include "stixel/anchors.h"
#include "stixel/world.h"

namespace stixel {

struct DepthMap {
  int width = 0, height = 0;
  std::vector<float> depth;  // row-major [height][width]; NaN where no stixel
};

// pyStixel-lib's derive_depth_map_from_stixel_world: per pixel the minimum d
// over the stixel rectangles [u - w/2, u + w/2] x [min(vT,vB), max(vT,vB)]
// (inclusive, clipped to the image; rectangles without width or height are
// skipped). Size: width/height if > 0, else the calibration's, else the
// embedded image's header, else the stixel extents. Throws Error if no size
// can be found or it exceeds 2^28 pixels.
DepthMap depth_map(const StixelWorld& world, int width = 0, int height = 0);

struct DepthRaster {
  int rows = 0, columns = 0;
  std::vector<float> depth;         // [rows][columns]; 0 where not valid
  std::vector<std::uint8_t> valid;  // 1 where a stixel covers the cell
};

// The evaluation raster of the latest reference (stixel_to_depth_map): per
// column the candidate with the highest P (first on ties), skipped if
// P < p_threshold (pass a negative value for no threshold); rows
// round-half-even(v_hat * H) in float32, clamped to [0, H-1], swapped if
// inverted, divided by v_scale; cells vt..vb (inclusive) of a [H/v_scale, U]
// raster get the candidate's decoded depth (anchor, or anchor * exp(d_res)).
DepthRaster prediction_depth_raster(const float* prediction, int attrs, int candidates,
                                    int columns, const Anchors& anchors, int image_height,
                                    int v_scale = 8, double p_threshold = -1.0);

}  // namespace stixel
