// Whole-file reads for the SHLE data parsers, with a size limit so that a wrong
// path (a device, a huge file) cannot exhaust memory.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace shle {

// The file's bytes. Throws shle::Error "<path>: <problem>" when it cannot be
// opened or read, is not a regular file (directories, FIFOs and devices are
// refused without blocking), or is larger than max_bytes ("<path>: ... larger
// than the limit of N bytes").
std::vector<std::uint8_t> read_file_bytes(const std::string& path, std::uint64_t max_bytes);

}  // namespace shle
