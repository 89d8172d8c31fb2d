// Pictures of a Stixel World in RGB buffers (the apps write them as PNG; the
// library does no image file I/O).
#pragma once

#include <cstdint>
#include <vector>

#include "stixel/colormap.h"
#include "stixel/projection.h"
#include "stixel/world.h"

namespace stixel {

struct RgbImage {
  int width = 0, height = 0;
  std::vector<std::uint8_t> pixels;  // row-major, interleaved R, G, B
};

struct OverlayOptions {
  double alpha = 0.5;           // stixel opacity, quantised to int(alpha * 255) like PIL
  double min_confidence = 0.5;  // draw stixels with confidence >= this (pyStixel's prob)
  bool color_by_cluster = false;  // jet of cluster / context.clusters instead of depth
};

// pyStixel-lib's draw_stixels_on_image, pixel for pixel: stixels sorted far to
// near (stable, d descending); each fills columns [u - w//2, u + w//2] and rows
// [min(vT,vB), max(vT,vB)] (inclusive, clipped; skipped if that leaves no width
// or height) of a transparent layer, later stixels overwriting earlier ones, in
// RdYlGn of (d - 5) / 45; the layer is alpha-composited onto the background with
// PIL's integer arithmetic. Throws Error if the background is not width*height*3
// bytes or alpha is outside [0, 1].
RgbImage render_overlay(const StixelWorld& world, const RgbImage& background,
                        const OverlayOptions& options = {});

struct BevOptions {
  int width = 1024, height = 1024;
  // Visible area in metres: lateral [-lateral_range, lateral_range] left to
  // right, forward [forward_min, forward_max] bottom to top.
  double lateral_range = 35.0, forward_min = 0.0, forward_max = 70.0;
  // Which 3D axes are "lateral" and "forward": optical frame (standard K, T = I)
  // x right / z forward = (0, 2, false); Waymo vehicle frame y left / x forward
  // = (1, 0, true) (flip: positive lateral values are drawn on the left).
  int lateral_axis = 0, forward_axis = 2;
  bool flip_lateral = false;
  enum class Color { Depth, Cluster, Confidence };
  Color color = Color::Depth;  // Cluster: jet by cluster id, noise grey
  double min_confidence = 0.5;
  bool grid = true;          // range rings and axes
  double ring_step = 10.0;   // metres between range rings
  Rgb background{20, 20, 20};
  // Fitted (render_bev_fitted): the stixels' opacity of the lines (dots are opaque).
  double line_alpha = 0.9;
};

// Bird's-eye view: per stixel (far to near) a line from its 3D top point to its
// bottom point and a 3x3 dot at the bottom point, in the lateral/forward plane.
RgbImage render_bev(const StixelWorld& world, const Projection& projection,
                    const BevOptions& options = {});

// pyStixel-lib's draw_stixels_birds_eye_view: the window fitted to the data (the
// min/max of the selected stixels' top and bottom points on the lateral and
// forward axes; lateral_range/forward_* and the grid are not used), each stixel
// in world order a 2-px line top -> bottom at line_alpha (0.9: alpha 229) and an
// opaque dot (Pillow's 3x3 ellipse: a plus) at the bottom point on a transparent
// layer composited over the background, drawn as Pillow draws them (its wide-line
// quad and scanline fill); positions int(clip(n * (size - 1))) as theirs. Cluster
// colours as theirs: (t, 1 - |2t - 1|, 1 - t) with t = id / max id, noise grey 127.
// One difference: pyStixel-lib projects the bottom points with a float32
// inverse, we use the double one for both (a point moves by < 1e-5 m).
RgbImage render_bev_fitted(const StixelWorld& world, const Projection& projection,
                           const BevOptions& options = {});

}  // namespace stixel
