// A tiny RGB rasteriser for the result plots: lines, rectangles, markers and a
// 5x7 bitmap font (digits, A-Z shown in capitals, a few symbols).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace shleapp {

struct Colour {
  std::uint8_t r, g, b;
};

class Canvas {
 public:
  Canvas(int width, int height, Colour background);
  int width() const { return w_; }
  int height() const { return h_; }
  const std::vector<std::uint8_t>& rgb() const { return px_; }

  void pixel(int x, int y, Colour c);
  void fill_rect(int x0, int y0, int x1, int y1, Colour c);  // inclusive corners, clipped
  // Line of the given thickness; dash > 0 draws dash px on, dash px off.
  void line(double x0, double y0, double x1, double y1, Colour c, int thickness = 1, int dash = 0);
  void square_marker(double x, double y, int half, Colour c);
  // Text with its top-left corner at (x, y), each font pixel drawn scale x scale.
  void text(int x, int y, const std::string& s, Colour c, int scale = 2);
  static int text_width(const std::string& s, int scale = 2);

 private:
  int w_, h_;
  std::vector<std::uint8_t> px_;
};

}  // namespace shleapp
