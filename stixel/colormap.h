// The matplotlib colormaps pyStixel-lib draws with, rebuilt bit-exactly: the
// 256-entry lookup tables of LinearSegmentedColormap (RdYlGn from its 11
// ColorBrewer colours, jet from its segment data), indexed and converted to
// bytes as `tuple(int(c * 255) for c in cmap(x)[:3])` does.
#pragma once

#include <array>
#include <cstdint>

namespace stixel {

using Rgb = std::array<std::uint8_t, 3>;

// cmap(x) for a float x: index clamp(int(x * 256), 0, 255); NaN gives black
// (matplotlib's transparent "bad" colour, drawn as 0, 0, 0).
Rgb rdylgn(double x);
Rgb jet(double x);

// pyStixel-lib's stixel colours: RdYlGn of (d - 5) / 45 (red near, green far),
// and jet of cluster / max_label.
Rgb depth_color(float d);
Rgb cluster_color(int cluster, int max_label);

}  // namespace stixel
