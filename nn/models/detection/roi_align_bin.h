// The RoIAlign bin sum of roi_align_kernel.h over a value type V (a float, or a GCC
// vector of floats in the ISA files), in an anonymous namespace: each including file
// compiles its own copy with its own ISA flags. With -ffp-contract=off every copy
// performs the same float operations in the same order, so all ISAs give the same bits.
#pragma once

#include <cstddef>

#include "nn/models/detection/roi_align_kernel.h"

namespace nn::detection {
namespace {

template <class V>
V roi_load(const float* p) {
  V v;
  __builtin_memcpy(&v, p, sizeof(V));
  return v;
}

template <class V>
void roi_bin_channels(const RoiBin& b, int c0, int c1) {
  constexpr int L = sizeof(V) / sizeof(float);
  const std::ptrdiff_t ld = b.channels;
  for (int c = c0; c + L <= c1; c += L) {
    V acc = V{};
    for (int s = 0; s < b.count_samples; ++s) {
      const RoiSample& sm = b.samples[s];
      const float* x = b.base + c;
      const V val = ((roi_load<V>(x + sm.p[0] * ld) * sm.w[0] + roi_load<V>(x + sm.p[1] * ld) * sm.w[1]) +
                     roi_load<V>(x + sm.p[2] * ld) * sm.w[2]) +
                    roi_load<V>(x + sm.p[3] * ld) * sm.w[3];
      acc = acc + val;
    }
    acc = acc / b.count;
    __builtin_memcpy(b.out + c, &acc, sizeof(V));
  }
}

template <class V>
void roi_bin_with(const RoiBin& b) {
  constexpr int L = sizeof(V) / sizeof(float);
  const int full = b.channels / L * L;
  roi_bin_channels<V>(b, 0, full);
  if (full < b.channels) roi_bin_channels<float>(b, full, b.channels);
}

}  // namespace
}  // namespace nn::detection
