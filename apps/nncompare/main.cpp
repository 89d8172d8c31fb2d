// nncompare: compares two safetensors files tensor by tensor (typically an `nnrun --dump`
// and a `scripts/torch_dump.py` dump of the same model and input), reports where they
// part ways and exits non-zero when a tensor is out of tolerance, so it works in CI.
// The comparison itself is weights/tensor_compare.h.
#include <cmath>
#include <cstdio>
#include <exception>
#include <regex>
#include <string>
#include <vector>

#include "apps/common/cli.h"
#include "apps/common/exec_env.h"
#include "weights/json.h"
#include "weights/safetensors.h"
#include "weights/tensor_compare.h"

namespace {

constexpr int kExitFailure = 1, kExitUsage = 2;

std::string fmt(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

// JSON has no Inf/NaN: such numbers are written as null.
std::string json_number(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

std::string json_ints(const std::vector<std::int64_t>& v) {
  std::string s = "[";
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? "," : "") + std::to_string(v[i]);
  return s + "]";
}

std::string shape_of(const weights::TensorReport& r) {
  if (r.status == weights::TensorStatus::OnlyInRef) return weights::shape_str(r.ref_shape);
  return weights::shape_str(r.shape);
}

// One line per tensor: what differs and by how much.
std::string describe(const weights::TensorReport& r) {
  using weights::TensorStatus;
  switch (r.status) {
    case TensorStatus::OnlyInA: return "only in A";
    case TensorStatus::OnlyInRef: return "only in the reference";
    case TensorStatus::DTypeMismatch:
      return std::string("dtype mismatch: ") + weights::dtype_name(r.dtype) + " vs reference " +
             weights::dtype_name(r.ref_dtype);
    case TensorStatus::ShapeMismatch:
      return "shape mismatch: " + weights::shape_str(r.shape) + " vs reference " + weights::shape_str(r.ref_shape);
    case TensorStatus::Ok:
    case TensorStatus::OutOfTolerance: break;
  }
  return weights::summary(r.values);
}

void print_text(const weights::FileComparison& c, const std::string& a, const std::string& ref,
                const weights::Tolerance& tol, bool brief) {
  std::printf("A: %s\nreference: %s\norder: %s\ntolerance: |a - ref| <= %s + %s * %s\n\n", a.c_str(), ref.c_str(),
              c.order_source.c_str(), fmt(tol.atol).c_str(), fmt(tol.rtol).c_str(),
              tol.per_element ? "|ref| (per element)" : "max|ref| of the tensor");
  std::size_t width = 4;
  for (const auto& r : c.tensors) width = std::max(width, r.name.size());
  for (const auto& r : c.tensors) {
    if (brief && !r.failed()) continue;
    const char* mark = r.failed() ? "FAIL" : r.status == weights::TensorStatus::Ok ? "ok  " : "--  ";
    std::printf("%s  %-*s  %-18s  %s\n", mark, static_cast<int>(width), r.name.c_str(), shape_of(r).c_str(),
                describe(r).c_str());
  }
  std::printf("\n%zu compared, %zu failed, %zu only in A, %zu only in the reference\n", c.compared, c.failures,
              c.only_in_a, c.only_in_ref);
  if (c.first_failure >= 0) {
    const auto& r = c.tensors[static_cast<std::size_t>(c.first_failure)];
    std::printf("first failure in network order: %s: %s\n", r.name.c_str(), describe(r).c_str());
  }
}

void print_json(const weights::FileComparison& c, const std::string& a, const std::string& ref,
                const weights::Tolerance& tol) {
  std::string s = "{\"a\":" + json::quote(a) + ",\"reference\":" + json::quote(ref) +
                  ",\"order\":" + json::quote(c.order_source) + ",\"tolerance\":{\"atol\":" + json_number(tol.atol) +
                  ",\"rtol\":" + json_number(tol.rtol) + ",\"rule\":" +
                  json::quote(tol.per_element ? "per_element" : "tensor_max") + "},\"tensors\":[";
  for (std::size_t i = 0; i < c.tensors.size(); ++i) {
    const auto& r = c.tensors[i];
    s += std::string(i ? "," : "") + "\n{\"name\":" + json::quote(r.name) +
         ",\"status\":" + json::quote(weights::tensor_status_name(r.status)) +
         ",\"failed\":" + (r.failed() ? "true" : "false");
    if (r.status != weights::TensorStatus::OnlyInRef)
      s += ",\"dtype\":" + json::quote(weights::dtype_name(r.dtype)) + ",\"shape\":" + json_ints(r.shape);
    if (r.status != weights::TensorStatus::OnlyInA)
      s += ",\"ref_dtype\":" + json::quote(weights::dtype_name(r.ref_dtype)) + ",\"ref_shape\":" + json_ints(r.ref_shape);
    if (r.status == weights::TensorStatus::Ok || r.status == weights::TensorStatus::OutOfTolerance) {
      const auto& v = r.values;
      s += ",\"count\":" + std::to_string(v.count) + ",\"max_abs_diff\":" + json_number(v.max_abs_diff) +
           ",\"max_abs_ref\":" + json_number(v.max_abs_ref) + ",\"max_rel_diff\":" + json_number(v.max_rel_diff) +
           ",\"mean_abs_diff\":" + json_number(v.mean_abs_diff) + ",\"worst_index\":" + json_ints(v.worst_coords) +
           ",\"worst_value\":" + json_number(v.worst_value) + ",\"worst_ref\":" + json_number(v.worst_ref) +
           ",\"nan\":" + std::to_string(v.nan) + ",\"inf\":" + std::to_string(v.inf) +
           ",\"ref_nan\":" + std::to_string(v.ref_nan) + ",\"ref_inf\":" + std::to_string(v.ref_inf) +
           ",\"failing_elements\":" + std::to_string(v.failing) + ",\"allowed\":" + json_number(v.allowed);
    }
    s += "}";
  }
  s += "],\n\"compared\":" + std::to_string(c.compared) + ",\"failures\":" + std::to_string(c.failures) +
       ",\"only_in_a\":" + std::to_string(c.only_in_a) + ",\"only_in_reference\":" + std::to_string(c.only_in_ref) +
       ",\"first_failure\":" +
       (c.first_failure >= 0 ? json::quote(c.tensors[static_cast<std::size_t>(c.first_failure)].name) : "null") +
       ",\"ok\":" + (c.failures == 0 ? "true" : "false") + "}\n";
  std::fputs(s.c_str(), stdout);
}

}  // namespace

int main(int argc, char** argv) {
  apps::apply_exec_environment("nncompare");
  std::vector<std::string> files;
  double rtol = weights::Tolerance{}.rtol, atol = weights::Tolerance{}.atol;
  bool per_element = false, as_json = false, brief = false;
  std::string filter;
  cli::Parser args("nncompare", "A.safetensors REF.safetensors [options]",
                   "Compares every tensor of A with the same-named tensor of the reference REF (e.g. an\n"
                   "`nnrun --dump` file with a `scripts/torch_dump.py` one): max |diff|, max |diff| / max |ref|,\n"
                   "mean |diff|, the coordinates of the worst element, NaN/Inf counts; shape and dtype\n"
                   "mismatches; tensors found in one file only. Tensors are listed in network order\n"
                   "(REF's dump.order metadata, else A's, else REF's data order).");
  args.positionals("A REF", "the file to check and the reference", &files);
  args.option("rtol", "R", "relative tolerance (default 1e-4): element i fails when\n"
              "                            |a_i - ref_i| > atol + rtol * max|ref| of that tensor", &rtol);
  args.option("atol", "A", "absolute tolerance (default 0)", &atol);
  args.flag("per-element", "scale rtol by |ref_i| of each element instead of max|ref| (numpy.allclose's rule)",
            &per_element);
  args.option("filter", "REGEX", "compare only tensors whose name contains a match of REGEX (ECMAScript)", &filter);
  args.flag("brief", "list only the failing tensors (the summary lines stay; with an nnrun dump\n"
            "                            against a torch dump, the modules our engine fuses are in one file only)", &brief);
  args.flag("json", "print the report as one JSON object instead of the table", &as_json);
  args.epilog("exit status: 0 every common tensor within tolerance, 1 a tensor out of tolerance or with a\n"
              "different shape or dtype (the report names the first in network order), 2 usage error or a\n"
              "file that cannot be read. Tensors in one file only are listed but do not fail.\n"
              "\nexample:\n  nncompare roadnn.dump.safetensors torch.dump.safetensors --rtol 1e-4 --filter '^features\\.'");
  args.parse(argc, argv);
  if (files.size() != 2) args.fail("expected two files, A and REF, got " + std::to_string(files.size()));
  if (!(rtol >= 0.0) || !std::isfinite(rtol)) args.fail("--rtol must be a finite number >= 0");
  if (!(atol >= 0.0) || !std::isfinite(atol)) args.fail("--atol must be a finite number >= 0");
  std::regex re;
  if (!filter.empty()) {
    try {
      re = std::regex(filter, std::regex::ECMAScript);
    } catch (const std::regex_error& e) {
      args.fail("--filter '" + filter + "': not a valid regular expression (" + e.what() + ")");
    }
  }
  weights::Tolerance tol;
  tol.rtol = rtol;
  tol.atol = atol;
  tol.per_element = per_element;

  try {
    const weights::SafeTensors a = weights::SafeTensors::load(files[0]);
    const weights::SafeTensors ref = weights::SafeTensors::load(files[1]);
    std::function<bool(const std::string&)> keep;
    if (!filter.empty()) keep = [&re](const std::string& name) { return std::regex_search(name, re); };
    const weights::FileComparison c = weights::compare_files(a, ref, tol, keep);
    if (as_json) print_json(c, files[0], files[1], tol);
    else print_text(c, files[0], files[1], tol, brief);
    return c.failures ? kExitFailure : 0;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "nncompare: out of memory\n");
    return kExitUsage;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "nncompare: %s\n", e.what());
    return kExitUsage;
  }
}
