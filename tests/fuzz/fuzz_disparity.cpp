// The disparity parsers of shle/disparity_io.h. Byte 0 chooses the format:
//   even: parse_pfm(rest)
//   odd:  parse_dat(rest after 9 bytes): width (int32 LE), height (int32 LE) and
//         fraction_bits (int8) come from bytes 1..9, the samples after them.
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "shle/disparity_io.h"
#include "tests/fuzz/fuzz_contract.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  if ((data[0] & 1) == 0) {
    fuzz::run([&] { (void)shle::parse_pfm(data + 1, size - 1, "fuzz.pfm"); });
    return 0;
  }
  if (size < 10) return 0;
  std::int32_t width, height;
  std::memcpy(&width, data + 1, 4);
  std::memcpy(&height, data + 5, 4);
  int bits = static_cast<std::int8_t>(data[9]);
  fuzz::run([&] { (void)shle::parse_dat(data + 10, size - 10, width, height, bits, "fuzz.dat"); });
  return 0;
}
