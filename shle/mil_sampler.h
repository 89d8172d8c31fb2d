// Window sampling of OpenCV 4.6's TrackerSamplerCSC::sampleImage: which windows
// around a position become positives, negatives or detection candidates.
#pragma once

#include <vector>

#include "shle/mil_random.h"

namespace shle {

struct MilWindow {
  int x, y;  // top-left pixel = top-left element of the window in the integral image
};

// Scans every top-left (c, r) of the rectangle around (x, y) row by row with
// r in [max(0, y - (int)inrad), min(rows - h - 1, y + (int)inrad)] and columns
// likewise (rows, cols: the image's size; the window stays one pixel clear of
// the last row and column). For EVERY candidate one uniform float is drawn
// first; the window is kept when that draw is below maxnum / (rectangle size)
// (in float) and outrad^2 <= dx^2 + dy^2 < inrad^2; at most maxnum are kept.
// The draws happen whatever the distance, so the generator's position depends
// on the rectangle's size, as in OpenCV. Empty when the rectangle is.
void mil_sample(int rows, int cols, int x, int y, int w, int h, float inrad, float outrad, int maxnum,
                CvRng* rng, std::vector<MilWindow>* out);

}  // namespace shle
