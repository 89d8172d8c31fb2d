// roadnn_compare_with_reference(): the public face of weights/tensor_compare.h for
// users' unit tests (roadnn/testing.hpp wraps it).
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "api/safetensors_file.h"
#include "api/status.h"
#include "api/text.h"
#include "roadnn/testing.h"
#include "weights/tensor_compare.h"

using roadnn_api::fail;
using roadnn_api::require;

namespace {

void set_message(roadnn_compare_result* out, const std::string& text) {
  const std::string line = roadnn_api::one_line(text, sizeof out->message - 1);
  std::memcpy(out->message, line.c_str(), line.size() + 1);
}

}  // namespace

extern "C" {

roadnn_tolerance roadnn_tolerance_default(void) {
  const weights::Tolerance t;
  return roadnn_tolerance{t.atol, t.rtol, t.per_element ? 1 : 0};
}

roadnn_status roadnn_compare_with_reference(const float* data, const int64_t* shape, size_t rank,
                                            const char* reference_path, const char* tensor_name,
                                            const roadnn_tolerance* tolerance, roadnn_compare_result* out) {
  return roadnn_api::guarded(ROADNN_ERROR_INVALID_ARGUMENT, [&] {
    const char* fn = "roadnn_compare_with_reference";
    require(out, fn, "out");
    std::memset(out, 0, sizeof *out);
    require(reference_path, fn, "reference_path");
    require(tensor_name, fn, "tensor_name");
    if (rank > ROADNN_COMPARE_MAX_RANK)
      fail(ROADNN_ERROR_INVALID_ARGUMENT, std::string(fn) + ": rank " + std::to_string(rank) + " exceeds " +
                                              std::to_string(ROADNN_COMPARE_MAX_RANK));
    if (rank > 0) require(shape, fn, "shape");
    weights::Tolerance tol;
    if (tolerance) {
      if (!(tolerance->atol >= 0.0) || !(tolerance->rtol >= 0.0) || !std::isfinite(tolerance->atol) ||
          !std::isfinite(tolerance->rtol))
        fail(ROADNN_ERROR_INVALID_ARGUMENT, std::string(fn) + ": tolerance atol and rtol must be finite and >= 0");
      tol.atol = tolerance->atol;
      tol.rtol = tolerance->rtol;
      tol.per_element = tolerance->per_element != 0;
    }
    const std::vector<std::int64_t> dims(shape, shape + rank);
    std::int64_t n = 1;
    for (std::int64_t d : dims) {
      if (d < 0) fail(ROADNN_ERROR_INVALID_ARGUMENT, std::string(fn) + ": negative dimension in shape " + weights::shape_str(dims));
      n *= d;
    }
    if (n > 0) require(data, fn, "data");

    const weights::SafeTensors ref = roadnn_api::load_safetensors_file(reference_path);
    if (!ref.has(tensor_name))
      fail(ROADNN_ERROR_INVALID_ARGUMENT, std::string(reference_path) + ": no tensor '" + tensor_name + "'");
    const weights::TensorInfo& info = ref.info(tensor_name);
    if (!weights::is_float_dtype(info.dtype))
      fail(ROADNN_ERROR_INVALID_ARGUMENT, std::string(reference_path) + ": tensor '" + tensor_name + "' is " +
                                              weights::dtype_name(info.dtype) + ", not a float tensor");
    const std::string what = "'" + std::string(tensor_name) + "' " + weights::shape_str(dims);
    out->rank = rank;
    if (info.shape != dims) {
      set_message(out, what + ": shape differs from the reference's " + weights::shape_str(info.shape) + " (" +
                           reference_path + ")");
      return;
    }
    out->shape_matches = 1;
    const std::vector<float> values = ref.f32(tensor_name);
    const weights::ValueComparison c = weights::compare_values(data, values.data(), dims, tol);
    out->ok = c.ok() ? 1 : 0;
    out->count = c.count;
    out->failing = c.failing;
    out->max_abs_diff = c.max_abs_diff;
    out->max_abs_ref = c.max_abs_ref;
    out->max_rel_diff = c.max_rel_diff;
    out->mean_abs_diff = c.mean_abs_diff;
    out->allowed = c.allowed;
    for (std::size_t i = 0; i < c.worst_coords.size(); ++i) out->worst[i] = c.worst_coords[i];
    out->worst_value = c.worst_value;
    out->worst_ref = c.worst_ref;
    out->nan_count = c.nan;
    out->inf_count = c.inf;
    out->ref_nan_count = c.ref_nan;
    out->ref_inf_count = c.ref_inf;
    char bound[96];
    std::snprintf(bound, sizeof bound, "; allowed |diff| <= %.4g + %.4g * %s", tol.atol, tol.rtol,
                  tol.per_element ? "|ref|" : "max|ref|");
    set_message(out, what + ": " + weights::summary(c) + bound);
  });
}

}  // extern "C"
