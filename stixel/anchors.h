// Depth anchors: the depth each of the N candidates of a column stands for.
// Every StixelNExT++ checkpoint uses (start, end, n) = (4, 66, 64) with tangent
// spacing; a linear set (e.g. 5..69, used by StixelNExT-Eval v1.0) is selectable.
#pragma once

#include <string>
#include <vector>

namespace stixel {

struct Anchors {
  enum class Kind { Tangent, Linear };
  Kind kind = Kind::Tangent;
  double start = 4.0, end = 66.0;
  std::vector<float> depth;  // depth[n], metres (what .stx1 files store)
  // The same depths in double before the rounding, as the reference keeps them
  // (numpy float64 tables); the depth-residual decoding starts from these. Empty
  // for a hand-made set: then depth[] is used.
  std::vector<double> exact;
  int size() const { return static_cast<int>(depth.size()); }
  double exact_at(int n) const { return exact.size() == depth.size() ? exact[n] : depth[n]; }
};

// d_i = start + (tan(theta_i) - tan 0) / (tan(a) - tan 0) * (end - start),
// theta_i = a * i / (n - 1), a = pi / 2.72; computed in double like numpy, then
// rounded to float (the precision .stx1 files store).
Anchors tangent_anchors(double start = 4.0, double end = 66.0, int n = 64);

// numpy.linspace(start, end, n) rounded to float.
Anchors linear_anchors(double start, double end, int n);

// Parses "tangent", "tangent:START,END,N", "linear:START,END,N" (the form
// anchor_spec() writes, used in weights metadata and on command lines).
// `source` names the origin in errors.
Anchors parse_anchor_spec(const std::string& spec, const std::string& source);

// "tangent:4,66,64" style description that parse_anchor_spec() reads back.
std::string anchor_spec(const Anchors& anchors);

}  // namespace stixel
