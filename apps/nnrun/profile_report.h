// nnrun --profile --format json|csv: the per-layer times of the timed passes in a
// machine-readable form. Per layer: name (the PyTorch module name the dump uses), op,
// output shape, FLOPs and estimated bytes moved per call, min/median/max ms over the
// calls, GFLOP/s at the median and its percent of the FMA peak measured in this run
// (nn/peak.h).
#pragma once

#include <string>
#include <vector>

#include "nn/profiler.h"

namespace nnrun {

struct ProfileRun {
  std::string model, isa;
  int threads = 0, passes = 0;
  double peak_gflops = 0;
  double forward_min = 0, forward_median = 0, forward_max = 0;  // ms
};

// The profilers' entries with at least one call; `level` names each table
// ("model" for the model's table, "layer" for the detectors' finer one).
struct ProfileTable {
  const nn::Profiler* profiler;
  const char* level;
};

std::string profile_json(const ProfileRun& run, const std::vector<ProfileTable>& tables);
std::string profile_csv(const ProfileRun& run, const std::vector<ProfileTable>& tables);

double median_of(std::vector<double> v);

}  // namespace nnrun
