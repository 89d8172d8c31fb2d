// roadnn testing helpers for C++ unit tests (GoogleTest-friendly, GoogleTest not needed):
// compare a roadnn output with a tensor of a reference safetensors file.
//
//   #include <roadnn/testing.hpp>
//   auto r = roadnn::testing::compare(out.data(), {1, 768, 40, 60}, "ref.safetensors", "features",
//                                     roadnn::testing::rtol(1e-4));
//   EXPECT_TRUE(r.ok) << r.message;   // "'features' [1, 768, 40, 60]: max|diff| ... at [0, 12, 3, 7] ..."
//
// Never throws: a reference that cannot be read gives ok == false, error == true and
// the reason in `message`, so the test fails with it. Rule: roadnn/testing.h.
#ifndef ROADNN_TESTING_HPP
#define ROADNN_TESTING_HPP

#include <cstdint>
#include <string>
#include <vector>

#include "roadnn/roadnn.h"
#include "roadnn/testing.h"

namespace roadnn {
namespace testing {

inline roadnn_tolerance default_tolerance() { return roadnn_tolerance_default(); }
// |d| <= atol + r * max|ref|
inline roadnn_tolerance rtol(double r, double atol = 0.0) { return roadnn_tolerance{atol, r, 0}; }
// |d_i| <= atol + r * |ref_i| (numpy.allclose's rule)
inline roadnn_tolerance rtol_per_element(double r, double atol = 0.0) { return roadnn_tolerance{atol, r, 1}; }

struct CompareResult {
  bool ok = false;
  bool error = false;  // the comparison could not be made (file, tensor name, arguments)
  double max_abs_diff = 0, max_rel_diff = 0, mean_abs_diff = 0, max_abs_ref = 0;
  std::vector<std::int64_t> worst;  // coordinates of the largest difference
  double worst_value = 0, worst_ref = 0;
  std::int64_t failing = 0, count = 0;
  std::string message;
  explicit operator bool() const { return ok; }
};

inline CompareResult compare(const float* data, const std::vector<std::int64_t>& shape, const std::string& reference,
                             const std::string& tensor, const roadnn_tolerance& tolerance = default_tolerance()) {
  roadnn_compare_result c;
  CompareResult r;
  const roadnn_status s = roadnn_compare_with_reference(data, shape.data(), shape.size(), reference.c_str(),
                                                        tensor.c_str(), &tolerance, &c);
  if (s != ROADNN_OK) {
    r.error = true;
    r.message = std::string(roadnn_status_name(s)) + ": " + roadnn_last_error();
    return r;
  }
  r.ok = c.ok != 0;
  r.max_abs_diff = c.max_abs_diff;
  r.max_rel_diff = c.max_rel_diff;
  r.mean_abs_diff = c.mean_abs_diff;
  r.max_abs_ref = c.max_abs_ref;
  r.worst.assign(c.worst, c.worst + c.rank);
  r.worst_value = c.worst_value;
  r.worst_ref = c.worst_ref;
  r.failing = c.failing;
  r.count = c.count;
  r.message = c.message;
  return r;
}

inline CompareResult compare(const std::vector<float>& data, const std::vector<std::int64_t>& shape,
                             const std::string& reference, const std::string& tensor,
                             const roadnn_tolerance& tolerance = default_tolerance()) {
  std::int64_t n = 1;
  for (std::int64_t d : shape) n *= d;
  if (n != static_cast<std::int64_t>(data.size())) {
    CompareResult r;
    r.error = true;
    r.message = "'" + tensor + "': " + std::to_string(data.size()) + " values for a shape of " + std::to_string(n);
    return r;
  }
  return compare(data.data(), shape, reference, tensor, tolerance);
}

}  // namespace testing
}  // namespace roadnn

#endif  // ROADNN_TESTING_HPP
