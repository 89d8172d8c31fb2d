#include "shle/file_read.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>

#include "shle/error.h"

namespace shle {

std::vector<std::uint8_t> read_file_bytes(const std::string& path, std::uint64_t max_bytes) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw Error(path + ": is a directory, not a file");
  errno = 0;
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!f) throw Error(path + ": cannot open (" + std::string(std::strerror(errno)) + ")");
  std::vector<std::uint8_t> bytes;
  std::uint8_t chunk[1 << 16];
  while (true) {
    std::size_t got = std::fread(chunk, 1, sizeof chunk, f.get());
    if (got > 0) {
      if (bytes.size() + got > max_bytes)
        throw Error(path + ": larger than " + std::to_string(max_bytes) + " bytes");
      bytes.insert(bytes.end(), chunk, chunk + got);
    }
    if (got < sizeof chunk) {
      if (std::ferror(f.get())) throw Error(path + ": read error (" + std::string(std::strerror(errno)) + ")");
      break;
    }
  }
  return bytes;
}

}  // namespace shle
