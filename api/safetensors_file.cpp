#include "api/safetensors_file.h"

#include <cstdio>
#include <string>

#include "api/status.h"
#include "weights/file_io.h"

namespace roadnn_api {

weights::SafeTensors load_safetensors_file(const char* path) {
  // Opening first (without blocking, regular files only) tells an I/O problem
  // (missing, unreadable, a FIFO or device) from a malformed file, which
  // weights::SafeTensors::load would report every failure as.
  std::uint64_t size = 0;
  std::string problem;
  std::FILE* f = weights::open_regular_file(path, &size, &problem);
  if (!f) {
    // "cannot open (Permission denied)": the file exists but is unreadable.
    if (problem.rfind("cannot open (", 0) == 0 && problem.find("No such file") == std::string::npos)
      problem.insert(std::string("cannot open").size(), " for reading");
    fail(ROADNN_ERROR_IO, std::string(path) + ": " + problem);
  }
  std::fclose(f);
  return weights::SafeTensors::load(path);
}

}  // namespace roadnn_api
