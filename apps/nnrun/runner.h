// One model behind `nnrun --model NAME`: it validates the input file's tensors,
// plans its memory, runs forward passes and writes its named outputs.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "nn/precision.h"
#include "nn/profiler.h"
#include "weights/safetensors.h"

namespace nnrun {

class Runner {
 public:
  virtual ~Runner() = default;
  // Names of every tensor the model reads from the weights file.
  virtual std::vector<std::string> used_tensors() const = 0;
  // One line describing the loaded model (configuration, packed weight size).
  virtual std::string describe() const = 0;
  // Checks the input file's tensors (throws with "<file>: ..." on a problem) and
  // plans the activation memory for them.
  virtual void prepare(const weights::SafeTensors& inputs) = 0;
  virtual void forward() = 0;
  // Adds the outputs of the last forward, in PyTorch's layout.
  virtual void write_outputs(weights::Writer& out) const = 0;
  virtual nn::Profiler& profiler() = 0;
  // A second, finer table (the detectors' backbone layers and RoI-head parts), or null.
  virtual nn::Profiler* layer_profiler() { return nullptr; }
  // Also write the RPN proposals; false when the model has none.
  virtual bool enable_proposal_dump() { return false; }
};

// Command-line settings a model may take.
struct RunOptions {
  nn::Precision precision = nn::Precision::F32;
};

struct ModelInfo {
  const char* name;
  const char* help;
  std::unique_ptr<Runner> (*make)(const std::string& name, const weights::SafeTensors& w,
                                  const RunOptions& options);
  bool has_precision;  // takes --precision bf16
};

// Every model nnrun knows, in --help order.
const std::vector<ModelInfo>& models();

std::unique_ptr<Runner> make_convnext(const std::string& name, const weights::SafeTensors& w,
                                      const RunOptions& options);

}  // namespace nnrun
