#include "nn/profiler.h"

#include <algorithm>
#include <cstdio>

namespace nn {

std::string nchw_str(const Shape& s) {
  return "[" + std::to_string(s.n) + ", " + std::to_string(s.c) + ", " + std::to_string(s.h) + ", " +
         std::to_string(s.w) + "]";
}

int Profiler::add(std::string layer, std::string op, std::string shape, double flops, double bytes) {
  ProfileEntry e;
  e.layer = std::move(layer);
  e.op = std::move(op);
  e.shape = std::move(shape);
  e.flops = flops;
  e.bytes = bytes;
  entries_.push_back(std::move(e));
  return static_cast<int>(entries_.size()) - 1;
}

void Profiler::reset_times() {
  for (auto& e : entries_) {
    e.total_ms = 0;
    e.calls = 0;
    e.samples.clear();
  }
}

void Profiler::reserve_samples(int calls) {
  for (auto& e : entries_) {
    e.samples.clear();
    e.samples.reserve(static_cast<std::size_t>(std::max(calls, 0)));
  }
}

std::string Profiler::table() const {
  double total = 0;
  for (const auto& e : entries_)
    if (e.calls) total += e.total_ms / e.calls;
  std::string out;
  char line[512];
  // The layer column fits the longest PyTorch name ("backbone.body.layer4.2.relu#1").
  int width = 18;
  for (const auto& e : entries_) width = std::max(width, static_cast<int>(std::min<std::size_t>(e.layer.size(), 60)));
  std::snprintf(line, sizeof line, "%-*s %-26s %-22s %10s %9s %6s\n", width, "layer", "op",
                "output (NCHW)", "mean ms", "GFLOP/s", "share");
  out += line;
  for (const auto& e : entries_) {
    if (!e.calls) continue;
    const double ms = e.total_ms / e.calls;
    char gf[32] = "-";
    if (e.flops > 0 && ms > 0) std::snprintf(gf, sizeof gf, "%.1f", e.flops / (ms * 1e6));
    std::snprintf(line, sizeof line, "%-*s %-26s %-22s %10.3f %9s %5.1f%%\n", width, e.layer.c_str(),
                  e.op.c_str(), e.shape.c_str(), ms, gf, total > 0 ? 100.0 * ms / total : 0.0);
    out += line;
  }
  std::snprintf(line, sizeof line, "%-*s %-26s %-22s %10.3f\n", width, "total", "", "", total);
  out += line;
  return out;
}

}  // namespace nn
