// Element-wise comparison of a tensor with a reference, and of two safetensors files
// tensor by tensor (nncompare, roadnn::testing). Written once here so that the
// command-line tool, the public test helper and our tests apply the same rule.
//
// Tolerance rule (documented in docs/NUMERICS.md): element i fails when
//     |a_i - ref_i| > atol + rtol * scale
// where scale = max |ref| over the whole tensor (the default, the rule our own
// PyTorch tests use: errors of float32 arithmetic grow with the tensor's magnitude,
// not with each element's), or scale = |ref_i| with Tolerance::per_element.
// Non-finite values: an element where both sides are NaN, or both the same
// infinity, matches (difference 0); any other element with a NaN or an infinity on
// either side has difference +inf and always fails.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "weights/safetensors.h"

namespace weights {

struct Tolerance {
  double atol = 0.0;
  double rtol = 1e-4;
  bool per_element = false;  // scale rtol by |ref_i| instead of max |ref|
};

// Statistics of one element-wise comparison.
struct ValueComparison {
  std::int64_t count = 0;
  double max_abs_diff = 0.0;   // +inf with a non-finite mismatch
  double max_abs_ref = 0.0;    // over the finite reference values
  double max_rel_diff = 0.0;   // max_abs_diff / max_abs_ref (0 if both 0, +inf if only the ref is 0)
  double mean_abs_diff = 0.0;  // +inf with a non-finite mismatch
  std::int64_t worst = -1;     // flat index of the largest difference (first on ties); -1 when empty
  std::vector<std::int64_t> worst_coords;  // the same as coordinates in the shape
  double worst_value = 0.0, worst_ref = 0.0;
  std::int64_t nan = 0, inf = 0, ref_nan = 0, ref_inf = 0;
  std::int64_t failing = 0;      // elements outside the tolerance
  std::int64_t first_failing = -1;  // flat index of the first of them
  double allowed = 0.0;          // atol + rtol * max|ref| (the tensor rule's bound)
  bool ok() const { return failing == 0; }
};

// Compares n values of `a` with `ref` (both in the same, row-major `shape`).
ValueComparison compare_values(const float* a, const float* ref, const std::vector<std::int64_t>& shape,
                               const Tolerance& tol);
ValueComparison compare_values(const double* a, const double* ref, const std::vector<std::int64_t>& shape,
                               const Tolerance& tol);

// One line on a comparison: "max|diff| 0.047 (0.01 of max|ref| 4.66) mean 0.0082 at
// [0, 6, 8, 698] (-4.703 vs -4.656); NaN/Inf ...; 71129 of 73728 elements out of tolerance".
std::string summary(const ValueComparison& c);

// Flat index -> coordinates in `shape` (row-major); {} for a scalar.
std::vector<std::int64_t> unravel_index(std::int64_t flat, const std::vector<std::int64_t>& shape);
// "[0, 12, 3, 7]"
std::string index_str(const std::vector<std::int64_t>& coords);

enum class TensorStatus {
  Ok,             // within tolerance
  OutOfTolerance, // values differ beyond the tolerance
  ShapeMismatch,
  DTypeMismatch,  // e.g. F32 vs I64: values are not compared
  OnlyInA,
  OnlyInRef,
};
const char* tensor_status_name(TensorStatus s);  // "ok", "out_of_tolerance", ...

struct TensorReport {
  std::string name;
  TensorStatus status = TensorStatus::Ok;
  DType dtype = DType::F32, ref_dtype = DType::F32;
  std::vector<std::int64_t> shape, ref_shape;
  ValueComparison values;  // filled for Ok and OutOfTolerance
  // A failure is anything but Ok and the "only in one file" entries, which are
  // listed but do not fail a comparison.
  bool failed() const {
    return status == TensorStatus::OutOfTolerance || status == TensorStatus::ShapeMismatch ||
           status == TensorStatus::DTypeMismatch;
  }
};

struct FileComparison {
  std::vector<TensorReport> tensors;  // in network order (see compare_files)
  std::string order_source;           // "dump.order of <file>" or "data offsets of <file>"
  // Index into `tensors` of the first failure in network order, -1 if none.
  std::int64_t first_failure = -1;
  std::size_t compared = 0, failures = 0, only_in_a = 0, only_in_ref = 0;
};

// Network order of a file's tensors: its `dump.order` metadata (comma-separated
// names; names absent from the file skipped) followed by any other tensor in data
// offset order; without dump.order, data offset order.
std::vector<std::string> network_order(const SafeTensors& st);

// Compares every tensor of `a` with the same-named tensor of `ref`. Order: the
// reference's dump.order, else a's, else the reference's data offsets; tensors of
// `a` not placed by that order follow in a's order. `keep(name)` (optional) selects
// the tensors looked at. Both sides must have the same dtype and shape, else that
// tensor is a DTypeMismatch / ShapeMismatch failure. F32/F16/BF16 compare as float,
// F64 and the integer and bool types as double (exact up to 2^53), all by the same rule.
FileComparison compare_files(const SafeTensors& a, const SafeTensors& ref, const Tolerance& tol,
                             const std::function<bool(const std::string&)>& keep = nullptr);

}  // namespace weights
