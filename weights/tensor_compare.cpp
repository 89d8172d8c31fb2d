#include "weights/tensor_compare.h"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <sstream>
#include <unordered_set>

namespace weights {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

template <class T>
ValueComparison compare_impl(const T* a, const T* ref, const std::vector<std::int64_t>& shape, const Tolerance& tol) {
  ValueComparison c;
  std::int64_t n = 1;
  for (std::int64_t d : shape) n *= d;
  c.count = n;
  // Pass 1: max |ref| (the tensor rule's scale) and the NaN/Inf counts.
  for (std::int64_t i = 0; i < n; ++i) {
    const double r = static_cast<double>(ref[i]), v = static_cast<double>(a[i]);
    if (std::isnan(r)) ++c.ref_nan;
    else if (std::isinf(r)) ++c.ref_inf;
    else c.max_abs_ref = std::max(c.max_abs_ref, std::fabs(r));
    if (std::isnan(v)) ++c.nan;
    else if (std::isinf(v)) ++c.inf;
  }
  c.allowed = tol.atol + tol.rtol * c.max_abs_ref;
  // Pass 2: differences, the worst element and the tolerance.
  double sum = 0.0;
  for (std::int64_t i = 0; i < n; ++i) {
    const double r = static_cast<double>(ref[i]), v = static_cast<double>(a[i]);
    double d;
    if (std::isfinite(r) && std::isfinite(v)) d = std::fabs(v - r);
    else if ((std::isnan(r) && std::isnan(v)) || r == v) d = 0.0;  // same NaN-ness or the same infinity
    else d = kInf;
    sum += d;
    if (d > c.max_abs_diff || c.worst < 0) {  // first on ties
      c.worst = i;
      c.max_abs_diff = d;
    }
    const double bound = tol.per_element ? tol.atol + tol.rtol * (std::isfinite(r) ? std::fabs(r) : 0.0) : c.allowed;
    if (d > bound) {
      if (c.failing == 0) c.first_failing = i;
      ++c.failing;
    }
  }
  if (n > 0) {
    c.mean_abs_diff = sum / static_cast<double>(n);
    c.worst_coords = unravel_index(c.worst, shape);
    c.worst_value = static_cast<double>(a[c.worst]);
    c.worst_ref = static_cast<double>(ref[c.worst]);
  }
  if (c.max_abs_ref > 0.0) c.max_rel_diff = c.max_abs_diff / c.max_abs_ref;
  else c.max_rel_diff = c.max_abs_diff > 0.0 ? kInf : 0.0;
  return c;
}

// Values of a non-float32-class tensor widened to double (F64 and integers).
std::vector<double> as_double(const SafeTensors& st, const TensorInfo& t) {
  const std::int64_t n = t.numel();
  std::vector<double> out(static_cast<std::size_t>(n));
  const std::uint8_t* p = st.raw(t.name);
  auto widen = [&](auto zero) {
    using T = decltype(zero);
    for (std::int64_t i = 0; i < n; ++i) {
      T v;
      std::memcpy(&v, p + i * sizeof(T), sizeof(T));
      out[static_cast<std::size_t>(i)] = static_cast<double>(v);
    }
  };
  switch (t.dtype) {
    case DType::F64: widen(double{}); break;
    case DType::I64: widen(std::int64_t{}); break;
    case DType::I32: widen(std::int32_t{}); break;
    case DType::I16: widen(std::int16_t{}); break;
    case DType::I8: widen(std::int8_t{}); break;
    case DType::U8:
    case DType::BOOL: widen(std::uint8_t{}); break;
    default: throw Error(st.source() + ": tensor '" + t.name + "': no double view of " + dtype_name(t.dtype));
  }
  return out;
}

std::vector<std::string> split_commas(const std::string& s) {
  std::vector<std::string> out;
  std::string item;
  std::istringstream in(s);
  while (std::getline(in, item, ','))
    if (!item.empty()) out.push_back(item);
  return out;
}

}  // namespace

ValueComparison compare_values(const float* a, const float* ref, const std::vector<std::int64_t>& shape,
                               const Tolerance& tol) {
  return compare_impl(a, ref, shape, tol);
}

ValueComparison compare_values(const double* a, const double* ref, const std::vector<std::int64_t>& shape,
                               const Tolerance& tol) {
  return compare_impl(a, ref, shape, tol);
}

std::string summary(const ValueComparison& v) {
  auto fmt = [](double x) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.4g", x);
    return std::string(buf);
  };
  std::string s = "max|diff| " + fmt(v.max_abs_diff) + " (" + fmt(v.max_rel_diff) + " of max|ref| " +
                  fmt(v.max_abs_ref) + ") mean " + fmt(v.mean_abs_diff);
  if (v.worst >= 0)
    s += " at " + index_str(v.worst_coords) + " (" + fmt(v.worst_value) + " vs " + fmt(v.worst_ref) + ")";
  if (v.nan || v.inf || v.ref_nan || v.ref_inf)
    s += "; NaN/Inf A " + std::to_string(v.nan) + "/" + std::to_string(v.inf) + ", ref " + std::to_string(v.ref_nan) +
         "/" + std::to_string(v.ref_inf);
  if (!v.ok()) s += "; " + std::to_string(v.failing) + " of " + std::to_string(v.count) + " elements out of tolerance";
  return s;
}

std::vector<std::int64_t> unravel_index(std::int64_t flat, const std::vector<std::int64_t>& shape) {
  std::vector<std::int64_t> coords(shape.size(), 0);
  for (std::size_t k = shape.size(); k-- > 0;) {
    if (shape[k] <= 0) return coords;
    coords[k] = flat % shape[k];
    flat /= shape[k];
  }
  return coords;
}

std::string index_str(const std::vector<std::int64_t>& coords) {
  std::string s = "[";
  for (std::size_t i = 0; i < coords.size(); ++i) s += (i ? ", " : "") + std::to_string(coords[i]);
  return s + "]";
}

const char* tensor_status_name(TensorStatus s) {
  switch (s) {
    case TensorStatus::Ok: return "ok";
    case TensorStatus::OutOfTolerance: return "out_of_tolerance";
    case TensorStatus::ShapeMismatch: return "shape_mismatch";
    case TensorStatus::DTypeMismatch: return "dtype_mismatch";
    case TensorStatus::OnlyInA: return "only_in_a";
    case TensorStatus::OnlyInRef: return "only_in_ref";
  }
  return "?";
}

std::vector<std::string> network_order(const SafeTensors& st) {
  std::vector<std::string> order;
  std::unordered_set<std::string> placed;
  if (auto it = st.metadata().find("dump.order"); it != st.metadata().end())
    for (const std::string& name : split_commas(it->second))
      if (st.has(name) && placed.insert(name).second) order.push_back(name);
  for (const std::string& name : st.names())
    if (placed.insert(name).second) order.push_back(name);
  return order;
}

FileComparison compare_files(const SafeTensors& a, const SafeTensors& ref, const Tolerance& tol,
                             const std::function<bool(const std::string&)>& keep) {
  FileComparison out;
  const bool ref_ordered = ref.metadata().count("dump.order") > 0;
  const bool a_ordered = a.metadata().count("dump.order") > 0;
  const SafeTensors& leader = ref_ordered || !a_ordered ? ref : a;
  out.order_source = std::string(leader.metadata().count("dump.order") ? "dump.order of " : "data offsets of ") +
                     leader.source();
  std::vector<std::string> names = network_order(leader);
  std::unordered_set<std::string> seen(names.begin(), names.end());
  const SafeTensors& other = &leader == &ref ? a : ref;
  for (const std::string& name : network_order(other))
    if (seen.insert(name).second) names.push_back(name);

  for (const std::string& name : names) {
    if (keep && !keep(name)) continue;
    TensorReport r;
    r.name = name;
    const bool in_a = a.has(name), in_ref = ref.has(name);
    if (in_a) {
      r.dtype = a.info(name).dtype;
      r.shape = a.info(name).shape;
    }
    if (in_ref) {
      r.ref_dtype = ref.info(name).dtype;
      r.ref_shape = ref.info(name).shape;
    }
    if (!in_ref) {
      r.status = TensorStatus::OnlyInA;
      ++out.only_in_a;
    } else if (!in_a) {
      r.status = TensorStatus::OnlyInRef;
      ++out.only_in_ref;
    } else if (r.dtype != r.ref_dtype) {
      r.status = TensorStatus::DTypeMismatch;
    } else if (r.shape != r.ref_shape) {
      r.status = TensorStatus::ShapeMismatch;
    } else {
      if (is_float_dtype(r.dtype)) {
        const std::vector<float> va = a.f32(name), vr = ref.f32(name);
        r.values = compare_values(va.data(), vr.data(), r.shape, tol);
      } else {
        const std::vector<double> va = as_double(a, a.info(name)), vr = as_double(ref, ref.info(name));
        r.values = compare_values(va.data(), vr.data(), r.shape, tol);
      }
      r.status = r.values.ok() ? TensorStatus::Ok : TensorStatus::OutOfTolerance;
      ++out.compared;
    }
    if (r.failed()) {
      ++out.failures;
      if (out.first_failure < 0) out.first_failure = static_cast<std::int64_t>(out.tensors.size());
    }
    out.tensors.push_back(std::move(r));
  }
  return out;
}

}  // namespace weights
