// stixelnext::parse_calibration (apps/stixelnext: K, T, width, height, or the authors'
// fx, fy, cx, cy) on json::parse
// of arbitrary text. That code is documented to throw std::runtime_error, which the
// contract accepts here (exactly that type, not its subclasses).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "apps/stixelnext/calibration.h"
#include "tests/fuzz/fuzz_contract.h"
#include "weights/json.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string_view text(reinterpret_cast<const char*>(data), size);
  fuzz::run(
      [&] {
        stixelnext::Calibration c = stixelnext::parse_calibration(json::parse(text, "calib.json"), "calib.json");
        // Our form carries a positive size; the authors' {fx, fy, cx, cy} form has none
        // (0 x 0: the image's own), never one side only or a negative one.
        if (c.K.size() != 9 || c.T.size() != 16) std::abort();
        if (c.width < 0 || c.height < 0 || (c.width == 0) != (c.height == 0)) std::abort();
      },
      fuzz::Plain::AcceptRuntimeError);
  return 0;
}
