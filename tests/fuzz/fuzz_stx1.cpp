// stixel::decode_stx1 on arbitrary bytes. A message that decodes must re-encode, and
// the re-encoding must decode to a world that encodes to the same bytes (the writer's
// output is canonical).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "stixel/stx1.h"
#include "tests/fuzz/fuzz_contract.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  stixel::StixelWorld world;
  if (!fuzz::run([&] { world = stixel::decode_stx1(data, size, "fuzz.stx1"); })) return 0;
  std::vector<std::uint8_t> once;
  fuzz::run([&] {
    once = stixel::encode_stx1(world);
    stixel::StixelWorld back = stixel::decode_stx1(once.data(), once.size(), "re-encoded");
    if (stixel::encode_stx1(back) != once) {
      std::fprintf(stderr, "encode(decode(encode(w))) != encode(w)\n");
      std::abort();
    }
  });
  return 0;
}
