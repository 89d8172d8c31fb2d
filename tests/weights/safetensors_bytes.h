// Builds raw safetensors files from a header string, for malformed-input tests.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "weights/safetensors.h"

namespace weights_test {

inline std::vector<std::uint8_t> file_bytes(const std::string& header, std::size_t data_bytes,
                                            std::uint64_t claimed_len) {
  // Appended piece by piece: with indexed stores into a sized vector, the aarch64 GCC 12
  // inlined a 2-byte header and reported a false -Wstringop-overflow.
  std::vector<std::uint8_t> out;
  out.reserve(8 + header.size() + data_bytes);
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<std::uint8_t>(claimed_len >> (8 * i)));
  out.insert(out.end(), header.begin(), header.end());
  for (std::size_t i = 0; i < data_bytes; ++i) out.push_back(static_cast<std::uint8_t>(i));
  return out;
}

// A file whose header length field is correct; `data_bytes` bytes of data follow.
inline std::vector<std::uint8_t> file_bytes(const std::string& header, std::size_t data_bytes) {
  return file_bytes(header, data_bytes, header.size());
}

// The message from_bytes throws for these bytes, or "" if it accepted them.
inline std::string load_error(const std::vector<std::uint8_t>& bytes) {
  try {
    weights::SafeTensors::from_bytes(bytes, "w.safetensors");
  } catch (const weights::Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace weights_test
