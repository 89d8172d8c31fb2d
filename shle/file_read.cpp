#include "shle/file_read.h"

#include "shle/error.h"
#include "weights/file_io.h"

namespace shle {

// One reader for every file of outside data (weights::read_file): regular files
// only, opened without blocking, the limit enforced while reading.
std::vector<std::uint8_t> read_file_bytes(const std::string& path, std::uint64_t max_bytes) {
  weights::FileBuffer buf;
  std::string problem = weights::read_file(path, max_bytes, &buf);
  if (!problem.empty()) throw Error(path + ": " + problem);
  return std::vector<std::uint8_t>(buf.data(), buf.data() + buf.size());
}

}  // namespace shle
