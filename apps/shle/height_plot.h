// heights.png: raw and Kalman-filtered height per frame with the ground-truth
// line, drawn with the small rasteriser in canvas.h.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "apps/shle/canvas.h"

namespace shleapp {

struct HeightPlotData {
  int frames = 0;                                  // x axis: frames 0..frames-1
  std::vector<std::pair<int, double>> raw, filtered;  // (frame, height m)
  bool has_gt = false;
  double gt = 0;
  bool has_scene = false;
  double scene = 0;
};

Canvas draw_height_plot(const HeightPlotData& data, int width = 1000, int height = 560);

// A "nice" tick step (1, 2, 2.5 or 5 times a power of ten) giving about `target`
// ticks over `span`.
double nice_step(double span, int target);

}  // namespace shleapp
