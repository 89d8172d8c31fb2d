// Non-owning views of NHWC float32 activations. PyTorch's NCHW appears only at
// the API boundary (see nn/layout.h).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace nn {

struct Shape {
  int n = 0, h = 0, w = 0, c = 0;
  std::size_t count() const {
    return static_cast<std::size_t>(n) * h * w * c;
  }
  bool operator==(const Shape& o) const { return n == o.n && h == o.h && w == o.w && c == o.c; }
  bool operator!=(const Shape& o) const { return !(*this == o); }
};

// Dense NHWC: element (n, y, x, ch) is data[((n*h + y)*w + x)*c + ch].
struct TensorView {
  float* data = nullptr;
  Shape shape;

  std::size_t count() const { return shape.count(); }
  std::size_t pixels() const { return static_cast<std::size_t>(shape.n) * shape.h * shape.w; }
  float* pixel(int n, int y, int x) const {
    return data + ((static_cast<std::size_t>(n) * shape.h + y) * shape.w + x) * shape.c;
  }
};

// "[n,h,w,c]" (NHWC order) for error messages.
std::string shape_str(const Shape& s);

struct ConstTensorView {
  const float* data = nullptr;
  Shape shape;
  ConstTensorView() = default;
  ConstTensorView(const float* d, Shape s) : data(d), shape(s) {}
  ConstTensorView(const TensorView& t) : data(t.data), shape(t.shape) {}  // NOLINT: implicit by design
  std::size_t count() const { return shape.count(); }
  std::size_t pixels() const { return static_cast<std::size_t>(shape.n) * shape.h * shape.w; }
  const float* pixel(int n, int y, int x) const {
    return data + ((static_cast<std::size_t>(n) * shape.h + y) * shape.w + x) * shape.c;
  }
};

}  // namespace nn
