#include "weights/tensor_spec.h"

#include <cstring>
#include <set>
#include <unordered_set>

#include "weights/quote_name.h"

namespace weights {
namespace {

// Scans the raw bit patterns, so nothing is converted or allocated: an
// all-ones exponent is Inf (zero mantissa) or NaN.
template <class Bits>
void check_finite(const SafeTensors& st, const TensorInfo& t, Bits exp_mask, Bits mant_mask) {
  const std::uint8_t* p = st.raw(t.name);
  const std::size_t n = static_cast<std::size_t>(t.numel());
  for (std::size_t i = 0; i < n; ++i) {
    Bits bits;
    std::memcpy(&bits, p + i * sizeof(Bits), sizeof(Bits));
    if ((bits & exp_mask) != exp_mask) continue;
    const char* what = (bits & mant_mask) ? "NaN" : "Inf";
    throw Error(st.source() + ": tensor " + quote_name(t.name) + " contains " + what +
                " (element " + std::to_string(i) + ")");
  }
}

}  // namespace

std::vector<std::string> check_tensors(const SafeTensors& st, const std::vector<TensorSpec>& specs) {
  std::unordered_set<std::string> expected;
  for (const TensorSpec& spec : specs) {
    expected.insert(spec.name);
    if (!st.has(spec.name)) {
      throw Error(st.source() + ": missing tensor " + quote_name(spec.name) + " (expected shape " +
                  shape_str(spec.shape) + ")");
    }
    const TensorInfo& t = st.info(spec.name);
    if (!is_float_dtype(t.dtype)) {
      throw Error(st.source() + ": tensor " + quote_name(t.name) + " has dtype " +
                  dtype_name(t.dtype) + ", expected a float type (F32, F16 or BF16)");
    }
    if (t.shape != spec.shape) {
      throw Error(st.source() + ": tensor " + quote_name(t.name) + " has shape " +
                  shape_str(t.shape) + ", expected " + shape_str(spec.shape));
    }
    switch (t.dtype) {
      case DType::F32:
        check_finite<std::uint32_t>(st, t, 0x7F800000u, 0x007FFFFFu);
        break;
      case DType::F16:
        check_finite<std::uint16_t>(st, t, 0x7C00u, 0x03FFu);
        break;
      default:  // BF16
        check_finite<std::uint16_t>(st, t, 0x7F80u, 0x007Fu);
        break;
    }
  }
  std::vector<std::string> unused;
  for (const TensorInfo& t : st.tensors()) {
    if (!expected.count(t.name)) unused.push_back(t.name);
  }
  return unused;
}

std::string unused_tensors_warning(const SafeTensors& st, const std::vector<std::string>& used,
                                   const std::string& what) {
  const std::set<std::string> known(used.begin(), used.end());
  std::vector<std::string> unused;
  for (const auto& n : st.names())
    if (!known.count(n)) unused.push_back(n);
  if (unused.empty()) return "";
  std::string list;
  for (std::size_t i = 0; i < unused.size() && i < 8; ++i) list += (i ? ", " : "") + quote_name(unused[i]);
  if (unused.size() > 8) list += ", ...";
  return st.source() + ": " + std::to_string(unused.size()) + " tensors not used by " + what + ": " + list;
}

}  // namespace weights
