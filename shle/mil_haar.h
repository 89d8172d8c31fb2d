// The image side of the MIL tracker as OpenCV 4.6 computes it: the float integral
// image and the random Haar features evaluated on it, with the same float
// operations in the same order, so that feature values are bitwise OpenCV's.
#pragma once

#include <cstddef>
#include <vector>

#include "shle/mil_random.h"
#include "shle/types.h"

namespace shle {

// cv::integral(image, sum, CV_32F), one channel: (height + 1) x (width + 1) floats,
// row 0 and column 0 zero. Sums beyond 2^24 round, and how they round depends
// on OpenCV's SIMD code path: each row is processed in blocks of `lanes`
// pixels whose running row sum is exact (sum = above + row prefix, one
// rounding), and the pixels after the last full block continue from the
// row prefix recovered as (left sum - sum above it), already rounded. `lanes`
// is the width of a 16-bit vector: 32 on AVX-512 (SKX) CPUs, 16 with AVX2, 8
// with SSE only, as OpenCV's run-time dispatch picks it; 0 means exact-prefix
// sums without blocks (OpenCV's plain C path). `channels` is how many
// interleaved channels the integrated image had (3 for a BGR frame, whose
// channel 0 `image` is): it only changes the last row or so, where OpenCV's
// 3-channel loop stops a block early to avoid reading past the buffer, and no
// window of the tracker reaches those rows.
struct MilIntegral {
  int width = 0, height = 0;  // of the image; the table is one larger each way
  std::vector<float> sum;
  std::size_t stride() const { return static_cast<std::size_t>(width) + 1; }
};
void mil_integral(const GrayView& image, int lanes, int channels, MilIntegral* out);
// The block width OpenCV 4.6's dispatcher uses for cv::integral on this CPU.
int opencv_integral_lanes();

// One random Haar feature of CvHaarEvaluator::FeatureHaar: 2 to 4 rectangles
// relative to the window's top-left, each weight divided by its area in float.
struct HaarFeature {
  struct Area {
    int x, y, w, h;
    float weight;  // the scaled weight: (float)w_i / (float)(area)
  };
  int count = 0;
  Area areas[4];
};

// Draws one feature for a window of w x h exactly as OpenCV does (rand() for
// the row, the column, the base width and height, then the type; redrawn until
// it fits strictly inside with an area of at least 9). False, without drawing,
// when no feature can fit the patch (OpenCV would loop forever), or when none
// was found within `max_attempts` draws.
bool draw_haar_feature(int w, int h, GlibcRand* rand, HaarFeature* out, long max_attempts = 10000000);

// The feature's value on the window whose top-left integral element is (x, y)
// and size w x h (sums clipped to the window as OpenCV's getSum does).
float haar_value(const HaarFeature& f, const MilIntegral& ii, int x, int y, int w, int h);

}  // namespace shle
