// A dump sink that wants every tensor and only counts them: for tests that need a sink set
// (a model with one takes its dump path) but not the tensors.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "nn/dump.h"

namespace testutil {

struct CountingDumpSink : nn::DumpSink {
  long tensors = 0;
  bool wants(const std::string&) const override { return true; }
  void tensor(const std::string&, const std::vector<std::int64_t>&, const float*, const std::string&) override {
    ++tensors;
  }
};

}  // namespace testutil
