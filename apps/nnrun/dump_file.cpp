#include "apps/nnrun/dump_file.h"

#include <algorithm>

#include "apps/common/output_files.h"

namespace nnrun {

DumpFile::DumpFile(const std::string& model, const std::string& filter) {
  if (!filter.empty()) {
    filter_ = std::regex(filter, std::regex::ECMAScript);
    filtered_ = true;
  }
  out_.set_metadata("dump.source", "roadnn");
  out_.set_metadata("dump.model", model);
}

bool DumpFile::wants(const std::string& name) const {
  if (std::find(order_.begin(), order_.end(), name) != order_.end()) return false;
  return !filtered_ || std::regex_search(name, filter_);
}

void DumpFile::tensor(const std::string& name, const std::vector<std::int64_t>& shape, const float* data,
                      const std::string& covers) {
  if (std::find(order_.begin(), order_.end(), name) != order_.end()) return;
  out_.add_f32(name, shape, data);
  order_.push_back(name);
  if (!covers.empty()) out_.set_metadata("dump.covers." + name, covers);
}

void DumpFile::write(const std::string& path) {
  std::string order;
  for (const auto& n : order_) order += (order.empty() ? "" : ",") + n;
  out_.set_metadata("dump.order", order);
  out_.set_metadata("dump.path", path_);
  out_.write(path, &outputs::temporary_file_hooks());
}

}  // namespace nnrun
