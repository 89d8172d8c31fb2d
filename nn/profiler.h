// Per-layer wall-clock times of a model's forward pass. Entries are created when a
// model plans its memory, so timing a forward allocates nothing.
#pragma once

#include <chrono>
#include <string>
#include <vector>

#include "nn/tensor.h"

namespace nn {

struct ProfileEntry {
  std::string layer;   // PyTorch module name of the output, as dumps name it: "features.1.0"
  std::string op;      // e.g. "dwconv 7x7"
  std::string shape;   // output shape, NCHW like PyTorch prints it
  double flops = 0;    // per call
  // Estimated bytes moved per call: inputs, weights and outputs each read or written
  // once (no cache effects, no scratch); 0 when unknown.
  double bytes = 0;
  double total_ms = 0;
  int calls = 0;
  // Per-call times (ms), kept when reserve_samples() made room: min/median/max over runs.
  std::vector<double> samples;
};

// An NHWC shape as PyTorch prints the NCHW tensor: "[n, c, h, w]".
std::string nchw_str(const Shape& s);

class Profiler {
 public:
  void clear() { entries_.clear(); }
  // Registers an entry at planning time; returns its index.
  int add(std::string layer, std::string op, std::string shape, double flops, double bytes = 0);
  // Clears the times; per-call samples are kept for up to `calls` calls per entry from
  // now on (storage reserved here, so timing still allocates nothing).
  void reset_times();
  void reserve_samples(int calls);
  bool enabled() const { return enabled_; }
  void set_enabled(bool on) { enabled_ = on; }
  const std::vector<ProfileEntry>& entries() const { return entries_; }
  // Adds one call of `ms` to entry `index` (for times measured by the caller, e.g. the
  // slowest thread's share of a layer interleaved with another).
  void record(int index, double ms) {
    auto& e = entries_[index];
    e.total_ms += ms;
    e.calls += 1;
    if (e.samples.size() < e.samples.capacity()) e.samples.push_back(ms);
  }
  // A fixed-width table: layer, op, shape, mean ms, GFLOP/s, share of the total.
  std::string table() const;

  // Times the enclosing scope into entry `index` when profiling is on.
  class Scope {
   public:
    Scope(Profiler* p, int index)
        : p_(p && p->enabled_ ? p : nullptr), index_(index),
          start_(p_ ? std::chrono::steady_clock::now() : std::chrono::steady_clock::time_point()) {}
    ~Scope() { stop(); }
    // Ends the timing before the scope does (once; later calls do nothing).
    void stop() {
      if (!p_) return;
      p_->record(index_, std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start_).count());
      p_ = nullptr;
    }
    Scope(const Scope&) = delete;
    Scope& operator=(const Scope&) = delete;

   private:
    Profiler* p_;
    int index_;
    std::chrono::steady_clock::time_point start_;
  };

 private:
  std::vector<ProfileEntry> entries_;
  bool enabled_ = false;
};

}  // namespace nn
