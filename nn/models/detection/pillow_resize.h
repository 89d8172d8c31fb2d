// Pillow's uint8 bilinear resize (Image.resize(size, BILINEAR), libImaging/Resample.c)
// bit for bit: separable, a horizontal pass to uint8 then a vertical pass to uint8
// (a pass is skipped when its side is unchanged); per output index the taps of a
// triangle filter stretched by max(in / out, 1), so shrinking is antialiased; the
// weights normalised in double and turned into 22-bit fixed point, the sums rounded
// and clamped to 0..255. detectron2's ResizeTransform runs it on every input.
#pragma once

#include <cstdint>
#include <vector>

namespace nn::detection {

// One pass's coefficients for in -> out samples along one axis.
struct PillowAxis {
  int in = 0, out = 0, ksize = 0;
  std::vector<int> first, count;  // per output index: the first tap and the number of taps
  std::vector<std::int32_t> k;    // out * ksize fixed-point weights
};

// precompute_coeffs + normalize_coeffs_8bpc for a bilinear filter.
PillowAxis pillow_bilinear_axis(int in, int out);

// An RGB8 (interleaved, 3 channels) resize planned once: coefficients and the
// intermediate rows; run() allocates nothing.
class PillowResize {
 public:
  void plan(int in_h, int in_w, int out_h, int out_w);
  // src: in_h x in_w x 3; dst: out_h x out_w x 3 (may equal nothing in src). Rows are
  // split over the thread team; every output byte is one thread's, so the result is
  // the same for any thread count.
  void run(const std::uint8_t* src, std::uint8_t* dst);
  int out_h() const { return v_.out; }
  int out_w() const { return h_.out; }

 private:
  PillowAxis h_, v_;
  int row_first_ = 0, row_count_ = 0;  // the source rows the vertical pass reads
  std::vector<std::uint8_t> tmp_;      // those rows after the horizontal pass
};

}  // namespace nn::detection
