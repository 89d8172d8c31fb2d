// stixelnext::parse_calibration (apps/stixelnext: K, T, width, height) on json::parse
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
        if (c.K.size() != 9 || c.T.size() != 16 || c.width < 1 || c.height < 1) std::abort();
      },
      fuzz::Plain::AcceptRuntimeError);
  return 0;
}
