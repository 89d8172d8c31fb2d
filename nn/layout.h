// Conversions between PyTorch's NCHW and the engine's NHWC at the API boundary.
#pragma once

namespace nn {

// dst[n][y][x][ch] = src[n][ch][y][x]. dst must not overlap src. Parallel over
// images and pixel blocks; a pure copy, so any thread count gives the same bytes.
void nchw_to_nhwc(const float* src, int n, int c, int h, int w, float* dst);
// dst[n][ch][y][x] = src[n][y][x][ch]. dst must not overlap src.
void nhwc_to_nchw(const float* src, int n, int c, int h, int w, float* dst);

}  // namespace nn
