#include "stixel/anchors.h"

#include "weights/quote_name.h"

#include <cfloat>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "stixel/error.h"

namespace stixel {
namespace {

constexpr int kMaxAnchors = 1 << 16;

std::string num(double v);

void check_range(double start, double end, int n, const char* what) {
  if (n < 2 || n > kMaxAnchors)
    throw Error(std::string(what) + " anchors: count must be in [2, " + std::to_string(kMaxAnchors) +
                "], got " + std::to_string(n));
  if (!std::isfinite(start) || !std::isfinite(end) || !(start > 0) || !(end > start))
    throw Error(std::string(what) + " anchors: need 0 < start < end, got start " +
                std::to_string(start) + ", end " + std::to_string(end));
  // The depths are float32: a range beyond float (1e-300, 1e300) would give 0 and
  // Inf depths that fail far from here.
  if (start < FLT_MIN || end > FLT_MAX)
    throw Error(std::string(what) + " anchors: start and end must lie in the float range [" + num(FLT_MIN) + ", " +
                num(FLT_MAX) + "], got start " + num(start) + ", end " + num(end));
}

// Float depths must stay finite, positive and strictly increasing (a range too
// narrow for float resolution collapses neighbours).
void check_depths(const Anchors& a, const char* what) {
  for (std::size_t i = 0; i < a.depth.size(); ++i) {
    const float d = a.depth[i];
    if (!std::isfinite(d) || !(d > 0) || (i > 0 && !(d > a.depth[i - 1])))
      throw Error(std::string(what) + " anchors: depth " + std::to_string(i) + " (" + num(d) +
                  ") is not finite, positive and above the previous one in float32; widen the range");
  }
}

// numpy.linspace(0, stop, n)[i] for i < n - 1: i * (stop / (n - 1)); the last
// element is `stop` itself.
double linspace_at(double start, double stop, int n, int i) {
  if (i == n - 1) return stop;
  const double step = (stop - start) / (n - 1);
  return i * step + start;
}

// Shortest text that reads back as the same double.
std::string num(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  double back = std::strtod(s.str().c_str(), nullptr);
  for (int p = 1; p <= 17; ++p) {
    std::ostringstream t;
    t.precision(p);
    t << v;
    if (std::strtod(t.str().c_str(), nullptr) == back) return t.str();
  }
  return s.str();
}

}  // namespace

Anchors tangent_anchors(double start, double end, int n) {
  check_range(start, end, n, "tangent");
  const double a = M_PI / 2.72;
  const double t0 = std::tan(0.0);
  const double tmax = std::tan(linspace_at(0.0, a, n, n - 1));
  Anchors out;
  out.kind = Anchors::Kind::Tangent;
  out.start = start;
  out.end = end;
  out.depth.resize(n);
  out.exact.resize(n);
  for (int i = 0; i < n; ++i) {
    const double t = std::tan(linspace_at(0.0, a, n, i));
    // Same operation order as the reference (normalise, then scale, then shift).
    const double d = start + (t - t0) / (tmax - t0) * (end - start);
    out.exact[i] = d;
    out.depth[i] = static_cast<float>(d);
  }
  check_depths(out, "tangent");
  return out;
}

Anchors linear_anchors(double start, double end, int n) {
  check_range(start, end, n, "linear");
  Anchors out;
  out.kind = Anchors::Kind::Linear;
  out.start = start;
  out.end = end;
  out.depth.resize(n);
  out.exact.resize(n);
  for (int i = 0; i < n; ++i) {
    out.exact[i] = linspace_at(start, end, n, i);
    out.depth[i] = static_cast<float>(out.exact[i]);
  }
  check_depths(out, "linear");
  return out;
}

Anchors parse_anchor_spec(const std::string& spec, const std::string& source) {
  const std::string where = source.empty() ? "anchors" : source;
  std::string kind = spec, args;
  std::size_t colon = spec.find(':');
  if (colon != std::string::npos) {
    kind = spec.substr(0, colon);
    args = spec.substr(colon + 1);
  }
  if (kind != "tangent" && kind != "linear")
    throw Error(where + ": unknown anchor kind " + weights::quote_name(kind) + " (expected tangent or linear)");
  if (args.empty()) {
    if (kind == "linear")
      throw Error(where + ": linear anchors need START,END,N (e.g. linear:5,69,64)");
    return tangent_anchors();
  }
  double v[3];
  const char* p = args.c_str();
  for (int k = 0; k < 3; ++k) {
    char* endp = nullptr;
    v[k] = std::strtod(p, &endp);
    if (endp == p || (k < 2 && *endp != ',') || (k == 2 && *endp != '\0'))
      throw Error(where + ": malformed anchor spec " + weights::quote_name(spec) + " (expected " + kind +
                  ":START,END,N)");
    p = endp + 1;
  }
  if (v[2] != std::floor(v[2]) || !(v[2] >= 2) || v[2] > kMaxAnchors)
    throw Error(where + ": anchor count must be an integer in [2, " + std::to_string(kMaxAnchors) +
                "] in " + weights::quote_name(spec));
  try {
    return kind == "tangent" ? tangent_anchors(v[0], v[1], static_cast<int>(v[2]))
                             : linear_anchors(v[0], v[1], static_cast<int>(v[2]));
  } catch (const Error& e) {
    throw Error(where + ": " + e.what());
  }
}

std::string anchor_spec(const Anchors& anchors) {
  return std::string(anchors.kind == Anchors::Kind::Tangent ? "tangent:" : "linear:") +
         num(anchors.start) + "," + num(anchors.end) + "," + std::to_string(anchors.size());
}

}  // namespace stixel
