// imageio::decode (apps/common/image_io.h, libjpeg-turbo / libpng) on arbitrary bytes.
// Byte 0 chooses the request: bits 0-1 want_channels (0, 1, 3, 4), bit 2 keep_16bit;
// the file is the rest. imageio::Error is the one extra error type accepted.
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "apps/common/image_io.h"
#include "tests/fuzz/fuzz_contract.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  static const int kChannels[4] = {0, 1, 3, 4};
  int want = kChannels[data[0] & 3];
  bool keep_16bit = (data[0] & 4) != 0;
  // The apps' default limit would let a 64 Mpx file take seconds per input; 4 Mpx
  // keeps the fuzzer fast and still drives the limit check (bit 3 of byte 0: 1 px,
  // so every decodable header meets the refusal path too).
  imageio::DecodeLimits limits;
  limits.max_pixels = (data[0] & 8) ? 1 : std::uint64_t(4) << 20;
  fuzz::run<imageio::Error>([&] {
    imageio::Image img = imageio::decode(data + 1, size - 1, "fuzz.img", want, keep_16bit, limits);
    if (img.width <= 0 || img.height <= 0) std::abort();
    if (want != 0 && img.channels != want) std::abort();
    std::size_t n = static_cast<std::size_t>(img.width) * img.height * img.channels;
    if (img.bit_depth == 16 ? img.u16.size() != n : img.u8.size() != n) std::abort();
  });
  return 0;
}
