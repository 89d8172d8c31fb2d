// nnrun --dump FILE [--dump-filter REGEX]: the intermediate tensors of one forward pass,
// under PyTorch's module names, collected into one safetensors file with the metadata
// of the dump contract (docs/NUMERICS.md): dump.order (network order), dump.source,
// dump.model, dump.covers.<name> and dump.path.
#pragma once

#include <regex>
#include <string>
#include <vector>

#include "nn/dump.h"
#include "weights/safetensors.h"

namespace nnrun {

class DumpFile : public nn::DumpSink {
 public:
  // `filter`: std::regex (ECMAScript), searched in each name; empty keeps every tensor.
  // Throws std::regex_error for a malformed expression.
  DumpFile(const std::string& model, const std::string& filter);

  bool wants(const std::string& name) const override;
  // A name seen twice keeps its first tensor (a runner dumps one forward).
  void tensor(const std::string& name, const std::vector<std::int64_t>& shape, const float* data,
              const std::string& covers) override;

  // dump.path: "fused", or what the runner unfused for the dump.
  void set_path(const std::string& path) { path_ = path; }
  // A free-form dump.<key> entry.
  void note(const std::string& key, const std::string& value) { out_.set_metadata("dump." + key, value); }
  std::size_t count() const { return order_.size(); }
  const std::vector<std::string>& order() const { return order_; }
  // Writes through the apps' temporary-and-rename machinery.
  void write(const std::string& path);

 private:
  bool filtered_ = false;
  std::regex filter_;
  std::string path_ = "fused";
  std::vector<std::string> order_;
  weights::Writer out_;
};

}  // namespace nnrun
