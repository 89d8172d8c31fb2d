// stixel::image_format / image_size (PNG IHDR, JPEG SOFn) on arbitrary bytes.
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "stixel/image_header.h"
#include "tests/fuzz/fuzz_contract.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz::run([&] {
    stixel::ImageFormat f = stixel::image_format(data, size);
    int w = -7, h = -7;
    bool ok = stixel::image_size(data, size, &w, &h);
    if (!ok && (w != -7 || h != -7)) {
      std::fprintf(stderr, "image_size failed but changed width/height\n");
      std::abort();
    }
    if (ok && f != stixel::ImageFormat::Png && f != stixel::ImageFormat::Jpeg) {
      std::fprintf(stderr, "image_size succeeded on a format image_format does not know\n");
      std::abort();
    }
  });
  return 0;
}
