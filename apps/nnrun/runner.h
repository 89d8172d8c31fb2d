// One model behind `nnrun --model NAME`: it validates the input file's tensors,
// plans its memory, runs forward passes and writes its named outputs.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "nn/dump.h"
#include "nn/isa.h"
#include "nn/models/convnext.h"
#include "nn/precision.h"
#include "nn/profiler.h"
#include "weights/safetensors.h"

namespace nnrun {

class Runner {
 public:
  virtual ~Runner() = default;
  // Names of every tensor the model reads from the weights file (for the unused-tensor
  // warning), or empty when the runner reports its own warnings().
  virtual std::vector<std::string> used_tensors() const = 0;
  // Warnings found while loading (the API runners' unused tensors), one line each.
  virtual std::vector<std::string> warnings() const { return {}; }
  // One line describing the loaded model (configuration, packed weight size).
  virtual std::string describe() const = 0;
  // Checks the input file's tensors (throws with "<file>: ..." on a problem) and
  // plans the activation memory for them.
  virtual void prepare(const weights::SafeTensors& inputs) = 0;
  // Models taking an RGB8 image (--image FILE) plan for it here; `source` names the
  // file in messages.
  virtual bool takes_image() const { return false; }
  virtual void prepare_rgb8(const std::uint8_t* rgb, int h, int w, const std::string& source) {
    (void)rgb, (void)h, (void)w;
    throw weights::Error(source + ": this model takes an input tensor file, not an image");
  }
  virtual void forward() = 0;
  // Adds the outputs of the last forward, in PyTorch's layout.
  virtual void write_outputs(weights::Writer& out) const = 0;
  // The per-layer time table, or null when the runner has none (the API runners).
  virtual nn::Profiler* profiler() { return nullptr; }
  // A second, finer table (the detectors' backbone layers and RoI-head parts), or null.
  virtual nn::Profiler* layer_profiler() { return nullptr; }
  // The next forward's intermediate tensors go to `dump` (null: off); notes the
  // dump's metadata (dump.path) on it.
  virtual void set_dump(nn::DumpSink* dump) = 0;
  // The dump.path metadata: "fused", or what the model computes apart for the dump.
  virtual std::string dump_path() const { return "fused"; }
  // Also write the RPN proposals; false when the model has none.
  virtual bool enable_proposal_dump() { return false; }
};

// Command-line settings a model may take.
struct RunOptions {
  nn::Precision precision = nn::Precision::F32;
  // For the API runners, which take them as model and session options (the internal
  // runners run under the main thread's settings).
  nn::Isa max_isa = nn::Isa::Avx512;
  int threads = 0;
};

struct ModelInfo {
  const char* name;
  const char* help;
  std::unique_ptr<Runner> (*make)(const std::string& name, const weights::SafeTensors& w,
                                  const RunOptions& options);
  bool has_precision;  // takes --precision bf16
  // The same model through the public API (used when no --profile is asked), or null.
  std::unique_ptr<Runner> (*make_api)(const std::string& name, const std::string& weights_path,
                                      const RunOptions& options);
};

// Every model nnrun knows, in --help order.
const std::vector<ModelInfo>& models();

std::unique_ptr<Runner> make_convnext(const std::string& name, const weights::SafeTensors& w,
                                      const RunOptions& options);
std::unique_ptr<Runner> make_convnext_api(const std::string& name, const std::string& weights_path,
                                          const RunOptions& options);

std::unique_ptr<Runner> make_stixelnext(const std::string& name, const weights::SafeTensors& w,
                                        const RunOptions& options);

// The configuration `name` (convnext_tiny/_small/_base) stands for; empty dims for
// "convnext" (any configuration).
nn::ConvNeXtConfig named_convnext_config(const std::string& name);

// The ConvNeXt input tensor 'input' [N,3,H,W] of an input file, checked (rank,
// channels, size, finite values; throws "<file>: ...").
struct ConvNeXtInput {
  int n, h, w;
};
ConvNeXtInput convnext_input(const weights::SafeTensors& in);

}  // namespace nnrun
