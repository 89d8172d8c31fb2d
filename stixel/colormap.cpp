#include "stixel/colormap.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace stixel {
namespace {

struct Node {
  double x, y0, y1;
};

// matplotlib's _create_lookup_table(N, data, gamma = 1) with the same
// floating-point operations, so the table matches to the last bit.
std::array<double, 256> lookup_table(const std::vector<Node>& data) {
  constexpr int N = 256;
  std::vector<double> x(data.size());
  for (std::size_t k = 0; k < data.size(); ++k) x[k] = data[k].x * (N - 1);
  std::array<double, N> lut{};
  lut[0] = data.front().y1;
  lut[N - 1] = data.back().y0;
  const double step = 1.0 / (N - 1);  // numpy.linspace(0, 1, N)
  for (int i = 1; i < N - 1; ++i) {
    const double xind = (N - 1) * (i * step);
    // numpy.searchsorted(x, xind), side='left'
    const std::size_t ind = std::lower_bound(x.begin(), x.end(), xind) - x.begin();
    const double distance = (xind - x[ind - 1]) / (x[ind] - x[ind - 1]);
    lut[i] = distance * (data[ind].y0 - data[ind - 1].y1) + data[ind - 1].y1;
  }
  for (double& v : lut) v = std::clamp(v, 0.0, 1.0);
  return lut;
}

struct Table {
  std::array<Rgb, 256> rgb;
};

// LinearSegmentedColormap.from_list: colours at numpy.linspace(0, 1, n).
Table from_list(const std::vector<std::array<int, 3>>& hex) {
  const int n = static_cast<int>(hex.size());
  const double step = 1.0 / (n - 1);
  std::array<std::array<double, 256>, 3> ch;
  for (int c = 0; c < 3; ++c) {
    std::vector<Node> nodes;
    for (int k = 0; k < n; ++k) {
      const double x = k == n - 1 ? 1.0 : k * step;
      const double y = hex[k][c] / 255.0;
      nodes.push_back({x, y, y});
    }
    ch[c] = lookup_table(nodes);
  }
  Table t;
  for (int i = 0; i < 256; ++i)
    for (int c = 0; c < 3; ++c) t.rgb[i][c] = static_cast<std::uint8_t>(ch[c][i] * 255.0);
  return t;
}

Table from_segments(const std::vector<Node>& r, const std::vector<Node>& g, const std::vector<Node>& b) {
  const std::array<std::array<double, 256>, 3> ch = {lookup_table(r), lookup_table(g), lookup_table(b)};
  Table t;
  for (int i = 0; i < 256; ++i)
    for (int c = 0; c < 3; ++c) t.rgb[i][c] = static_cast<std::uint8_t>(ch[c][i] * 255.0);
  return t;
}

const Table& rdylgn_table() {
  // ColorBrewer RdYlGn, 11 classes (matplotlib's _RdYlGn_data is these / 255).
  static const Table t = from_list({{165, 0, 38},    {215, 48, 39},   {244, 109, 67},
                                    {253, 174, 97},  {254, 224, 139}, {255, 255, 191},
                                    {217, 239, 139}, {166, 217, 106}, {102, 189, 99},
                                    {26, 152, 80},   {0, 104, 55}});
  return t;
}

const Table& jet_table() {
  static const Table t = from_segments(
      {{0.0, 0, 0}, {0.35, 0, 0}, {0.66, 1, 1}, {0.89, 1, 1}, {1.0, 0.5, 0.5}},
      {{0.0, 0, 0}, {0.125, 0, 0}, {0.375, 1, 1}, {0.64, 1, 1}, {0.91, 0, 0}, {1.0, 0, 0}},
      {{0.0, 0.5, 0.5}, {0.11, 1, 1}, {0.34, 1, 1}, {0.65, 0, 0}, {1.0, 0, 0}});
  return t;
}

Rgb lookup(const Table& t, double x) {
  if (std::isnan(x)) return {0, 0, 0};
  double xa = x * 256.0;
  if (xa == 256.0) xa = 255.0;
  int idx;
  if (xa < 0)
    idx = 0;  // "under" defaults to the first colour
  else if (xa >= 256.0)
    idx = 255;  // "over" defaults to the last colour
  else
    idx = static_cast<int>(xa);
  return t.rgb[idx];
}

}  // namespace

Rgb rdylgn(double x) { return lookup(rdylgn_table(), x); }
Rgb jet(double x) { return lookup(jet_table(), x); }

Rgb depth_color(float d) { return rdylgn((static_cast<double>(d) - 5.0) / (50.0 - 5.0)); }

Rgb cluster_color(int cluster, int max_label) {
  if (max_label <= 0) return jet(0.0);
  return jet(static_cast<double>(cluster) / max_label);
}

}  // namespace stixel
