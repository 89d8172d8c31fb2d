// weights::SafeTensors::from_bytes (the in-memory form of load()) on arbitrary bytes;
// a file that validates must then give every tensor's values without surprises.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "tests/fuzz/fuzz_contract.h"
#include "weights/safetensors.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz::run([&] {
    weights::SafeTensors st =
        weights::SafeTensors::from_bytes(std::vector<std::uint8_t>(data, data + size), "fuzz.safetensors");
    (void)st.metadata();
    for (const weights::TensorInfo& t : st.tensors()) {
      const weights::TensorInfo& again = st.info(t.name);
      std::uint64_t bytes = static_cast<std::uint64_t>(t.numel()) * weights::dtype_size(t.dtype);
      if (&again != &t || t.end - t.begin != bytes || t.end > size) {
        std::fprintf(stderr, "validated tensor with inconsistent info\n");
        std::abort();
      }
      const std::uint8_t* raw = st.raw(t.name);
      if (bytes && raw == nullptr) std::abort();
      if (weights::is_float_dtype(t.dtype)) {
        if (st.f32(t.name).size() != static_cast<std::size_t>(t.numel())) std::abort();
      } else if (t.dtype == weights::DType::I64 || t.dtype == weights::DType::I32) {
        if (st.i64(t.name).size() != static_cast<std::size_t>(t.numel())) std::abort();
      }
    }
    (void)st.names();
  });
  return 0;
}
