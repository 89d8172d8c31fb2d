#include "weights/safetensors.h"

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <limits>
#include <system_error>

#include "weights/file_io.h"
#include "weights/json.h"
#include "weights/quote_name.h"

namespace weights {
namespace {

struct DTypeEntry {
  DType dtype;
  const char* name;
  std::size_t size;
};

constexpr DTypeEntry kDTypes[] = {
    {DType::F64, "F64", 8},  {DType::F32, "F32", 4}, {DType::F16, "F16", 2},
    {DType::BF16, "BF16", 2}, {DType::I64, "I64", 8}, {DType::I32, "I32", 4},
    {DType::I16, "I16", 2},  {DType::I8, "I8", 1},   {DType::U8, "U8", 1},
    {DType::BOOL, "BOOL", 1},
};

const DTypeEntry& dtype_entry(DType dtype) {
  for (const DTypeEntry& e : kDTypes) {
    if (e.dtype == dtype) return e;
  }
  throw Error("invalid DType value " + std::to_string(static_cast<int>(dtype)));
}

bool dtype_from_name(const std::string& name, DType* out) {
  for (const DTypeEntry& e : kDTypes) {
    if (name == e.name) {
      *out = e.dtype;
      return true;
    }
  }
  return false;
}

// Safetensors files are loaded whole; this only guards against reading an
// endless device into memory.
constexpr std::uint64_t kMaxFileBytes = 1ull << 46;

bool mul_overflows(std::uint64_t a, std::uint64_t b, std::uint64_t* out) {
  if (a != 0 && b > std::numeric_limits<std::uint64_t>::max() / a) return true;
  *out = a * b;
  return false;
}

// Element count of a shape whose dims are already known to be non-negative;
// false if it does not fit in int64.
bool checked_numel(const std::vector<std::int64_t>& shape, std::uint64_t* out) {
  for (std::int64_t d : shape) {
    if (d == 0) {
      *out = 0;
      return true;
    }
  }
  std::uint64_t n = 1;
  for (std::int64_t d : shape) {
    if (mul_overflows(n, static_cast<std::uint64_t>(d), &n)) return false;
  }
  if (n > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max())) return false;
  *out = n;
  return true;
}

bool checked_nbytes(const std::vector<std::int64_t>& shape, DType dtype, std::uint64_t* out) {
  std::uint64_t numel = 0;
  if (!checked_numel(shape, &numel)) return false;
  return !mul_overflows(numel, dtype_size(dtype), out);
}

std::string describe_json(const json::Value& v) {
  switch (v.type()) {
    case json::Value::Type::Null: return "null";
    case json::Value::Type::Bool: return v.boolean() ? "true" : "false";
    case json::Value::Type::Number: return v.number_text();
    case json::Value::Type::String: return "a string";
    case json::Value::Type::Array: return "an array";
    case json::Value::Type::Object: return "an object";
  }
  return "?";
}

bool starts_with(const std::string& s, const char* prefix) {
  return s.compare(0, std::strlen(prefix), prefix) == 0;
}

std::uint64_t read_u64_le(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

struct HeaderEntry {
  TensorInfo info;
  std::size_t header_index;
  bool padding;
};

}  // namespace

const char* dtype_name(DType dtype) { return dtype_entry(dtype).name; }
std::size_t dtype_size(DType dtype) { return dtype_entry(dtype).size; }
bool is_float_dtype(DType dtype) {
  return dtype == DType::F32 || dtype == DType::F16 || dtype == DType::BF16;
}

float f16_to_f32(std::uint16_t h) {
  std::uint32_t sign = static_cast<std::uint32_t>(h & 0x8000u) << 16;
  std::uint32_t exp = (h >> 10) & 0x1Fu;
  std::uint32_t mant = h & 0x3FFu;
  std::uint32_t bits;
  if (exp == 0) {
    if (mant == 0) {
      bits = sign;
    } else {
      // Subnormal half: shift the mantissa up until its implicit bit appears;
      // every half subnormal is a normal float.
      int shift = 0;
      while (!(mant & 0x400u)) {
        mant <<= 1;
        ++shift;
      }
      mant &= 0x3FFu;
      bits = sign | (static_cast<std::uint32_t>(127 - 15 + 1 - shift) << 23) | (mant << 13);
    }
  } else if (exp == 0x1F) {
    bits = sign | 0x7F800000u | (mant << 13);  // Inf, or NaN keeping its payload
  } else {
    bits = sign | ((exp + 127 - 15) << 23) | (mant << 13);
  }
  float f;
  std::memcpy(&f, &bits, sizeof f);
  return f;
}

float bf16_to_f32(std::uint16_t b) {
  std::uint32_t bits = static_cast<std::uint32_t>(b) << 16;
  float f;
  std::memcpy(&f, &bits, sizeof f);
  return f;
}

std::string shape_str(const std::vector<std::int64_t>& shape) {
  std::string s = "[";
  for (std::size_t i = 0; i < shape.size(); ++i) {
    if (i) s += ", ";
    s += std::to_string(shape[i]);
  }
  return s + "]";
}

std::int64_t TensorInfo::numel() const {
  // A zero anywhere makes the product zero, even when the other dimensions multiply
  // past int64 (a valid empty tensor): check before multiplying, which would overflow.
  for (std::int64_t d : shape)
    if (d == 0) return 0;
  std::int64_t n = 1;
  for (std::int64_t d : shape)
    if (__builtin_mul_overflow(n, d, &n))
      throw Error("tensor " + quote_name(name) + " of shape " + shape_str(shape) + " has more than 2^63 elements");
  return n;
}

void SafeTensors::fail(const std::string& problem) const { throw Error(source_ + ": " + problem); }

SafeTensors SafeTensors::load(const std::string& path) {
  std::error_code ec;
  auto status = std::filesystem::status(path, ec);
  if (!ec && std::filesystem::exists(status) && !std::filesystem::is_regular_file(status)) {
    throw Error(path + ": not a regular file");
  }
  FileBuffer bytes;
  std::string problem = read_file(path, kMaxFileBytes, &bytes);
  if (!problem.empty()) throw Error(path + ": " + problem);
  return from_buffer(std::move(bytes), path);
}

SafeTensors SafeTensors::from_bytes(std::vector<std::uint8_t> bytes, const std::string& source) {
  return from_buffer(FileBuffer(std::move(bytes)), source);
}

SafeTensors SafeTensors::from_buffer(FileBuffer bytes, const std::string& source) {
  SafeTensors st;
  st.source_ = source;
  st.bytes_ = std::make_shared<const FileBuffer>(std::move(bytes));
  const std::uint64_t size = st.bytes_->size();
  if (size < 8) {
    st.fail("file is " + std::to_string(size) +
            " bytes, too short for the 8-byte header length (truncated?)");
  }
  std::uint64_t header_len = read_u64_le(st.bytes_->data());
  if (header_len > kMaxHeaderBytes) {
    st.fail("header length " + std::to_string(header_len) + " exceeds the limit of " +
            std::to_string(kMaxHeaderBytes) + " bytes");
  }
  // size >= 8 here, so the subtraction cannot wrap.
  if (header_len > size - 8) {
    st.fail("header length " + std::to_string(header_len) +
            " runs past the end of the file (size " + std::to_string(size) + ")");
  }
  st.data_start_ = static_cast<std::size_t>(8 + header_len);
  st.parse_header(header_len);
  return st;
}

void SafeTensors::parse_header(std::uint64_t header_len) {
  json::Value root;
  try {
    root = json::parse(std::string_view(reinterpret_cast<const char*>(bytes_->data() + 8),
                                        static_cast<std::size_t>(header_len)),
                       source_ + ": header");
  } catch (const json::Error& e) {
    throw Error(e.what());
  }
  if (!root.is_object()) fail("header is " + describe_json(root) + ", expected a JSON object");

  std::vector<HeaderEntry> entries;
  for (const auto& [name, entry] : root.object()) {
    if (name == "__metadata__") {
      if (!entry.is_object()) fail("__metadata__ is " + describe_json(entry) + ", expected an object");
      for (const auto& [key, value] : entry.object()) {
        if (!value.is_string()) {
          fail("__metadata__ value for key " + quote_name(key) + " is " + describe_json(value) +
               ", expected a string");
        }
        metadata_.emplace(key, value.str());
      }
      continue;
    }
    const std::string label = "tensor " + quote_name(name);
    if (!entry.is_object()) fail(label + ": entry is " + describe_json(entry) + ", expected an object");
    const json::Value* dtype_v = nullptr;
    const json::Value* shape_v = nullptr;
    const json::Value* offsets_v = nullptr;
    for (const auto& [field, value] : entry.object()) {
      if (field == "dtype") {
        dtype_v = &value;
      } else if (field == "shape") {
        shape_v = &value;
      } else if (field == "data_offsets") {
        offsets_v = &value;
      } else {
        fail(label + ": unexpected field " + quote_name(field) +
             " (expected only dtype, shape, data_offsets)");
      }
    }
    if (!dtype_v) fail(label + ": missing field 'dtype'");
    if (!shape_v) fail(label + ": missing field 'shape'");
    if (!offsets_v) fail(label + ": missing field 'data_offsets'");

    HeaderEntry he;
    he.info.name = name;
    he.header_index = entries.size();
    he.padding = starts_with(name, kPaddingPrefix);
    if (!dtype_v->is_string()) fail(label + ": dtype is " + describe_json(*dtype_v) + ", expected a string");
    if (!dtype_from_name(dtype_v->str(), &he.info.dtype)) {
      fail(label + ": unknown dtype " + quote_name(dtype_v->str()));
    }

    if (!shape_v->is_array()) fail(label + ": shape is " + describe_json(*shape_v) + ", expected an array");
    const auto& dims = shape_v->array();
    if (dims.size() > kMaxRank) {
      fail(label + ": rank " + std::to_string(dims.size()) + " exceeds the maximum of " +
           std::to_string(kMaxRank));
    }
    for (std::size_t i = 0; i < dims.size(); ++i) {
      std::uint64_t d = 0;
      if (!dims[i].as_u64(&d) ||
          d > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max())) {
        fail(label + ": shape dimension " + std::to_string(i) + " is " + describe_json(dims[i]) +
             ", expected a non-negative integer");
      }
      he.info.shape.push_back(static_cast<std::int64_t>(d));
    }
    std::uint64_t nbytes = 0;
    if (!checked_nbytes(he.info.shape, he.info.dtype, &nbytes)) {
      fail(label + ": shape " + shape_str(he.info.shape) + " is too large (element count overflows)");
    }

    std::uint64_t range[2] = {0, 0};
    if (!offsets_v->is_array() || offsets_v->array().size() != 2 ||
        !offsets_v->array()[0].as_u64(&range[0]) || !offsets_v->array()[1].as_u64(&range[1])) {
      fail(label + ": data_offsets must be an array of two non-negative integers");
    }
    he.info.begin = range[0];
    he.info.end = range[1];
    const std::string offsets_text =
        "data_offsets [" + std::to_string(range[0]) + ", " + std::to_string(range[1]) + "]";
    if (range[1] < range[0]) fail(label + ": " + offsets_text + " end before they begin");
    if (range[1] - range[0] != nbytes) {
      fail(label + ": " + offsets_text + " hold " + std::to_string(range[1] - range[0]) +
           " bytes, but shape " + shape_str(he.info.shape) + " of " + dtype_name(he.info.dtype) +
           " needs " + std::to_string(nbytes));
    }
    if (he.padding && (he.info.dtype != DType::U8 || he.info.shape.size() != 1)) {
      fail("padding " + label + " must be a rank-1 U8 tensor");
    }
    entries.push_back(std::move(he));
  }

  // The data section must be tiled exactly: sorted by offset, each tensor starts
  // where the previous one ended. Empty tensors sort before a non-empty one at
  // the same offset; header order breaks the remaining ties.
  std::sort(entries.begin(), entries.end(), [](const HeaderEntry& a, const HeaderEntry& b) {
    if (a.info.begin != b.info.begin) return a.info.begin < b.info.begin;
    if (a.info.end != b.info.end) return a.info.end < b.info.end;
    return a.header_index < b.header_index;
  });
  const std::uint64_t data_size = bytes_->size() - data_start_;
  std::uint64_t pos = 0;
  const TensorInfo* prev = nullptr;
  for (const HeaderEntry& e : entries) {
    const TensorInfo& t = e.info;
    if (t.begin > pos) {
      if (!prev) {
        fail("gap of " + std::to_string(t.begin) + " bytes at the start of the data, before tensor " +
             quote_name(t.name) + " (begins at " + std::to_string(t.begin) + ")");
      }
      fail("gap of " + std::to_string(t.begin - pos) + " bytes between tensor " +
           quote_name(prev->name) + " (ends at " + std::to_string(pos) + ") and tensor " +
           quote_name(t.name) + " (begins at " + std::to_string(t.begin) + ")");
    }
    if (t.begin < pos) {
      fail("overlap: tensor " + quote_name(t.name) + " (begins at " + std::to_string(t.begin) +
           ") overlaps tensor " + quote_name(prev->name) + " (ends at " + std::to_string(pos) + ")");
    }
    pos = t.end;
    prev = &t;
  }
  if (pos > data_size) {
    fail("data truncated: tensor " + quote_name(prev->name) + " ends at byte " + std::to_string(pos) +
         " of the data, but only " + std::to_string(data_size) + " data bytes follow the header");
  }
  if (pos < data_size) {
    fail(std::to_string(data_size - pos) + " trailing bytes after the last tensor (data ends at " +
         std::to_string(pos) + ", the file has " + std::to_string(data_size) +
         " data bytes after the header)");
  }

  for (HeaderEntry& e : entries) {
    if (e.padding) continue;
    index_.emplace(e.info.name, tensors_.size());
    tensors_.push_back(std::move(e.info));
  }
}

bool SafeTensors::has(const std::string& name) const { return index_.count(name) != 0; }

const TensorInfo& SafeTensors::info(const std::string& name) const {
  auto it = index_.find(name);
  if (it == index_.end()) fail("no tensor " + quote_name(name));
  return tensors_[it->second];
}

std::vector<std::string> SafeTensors::names() const {
  std::vector<std::string> out;
  out.reserve(tensors_.size());
  for (const TensorInfo& t : tensors_) out.push_back(t.name);
  return out;
}

const std::uint8_t* SafeTensors::raw(const std::string& name) const {
  return bytes_->data() + data_start_ + info(name).begin;
}

std::vector<float> SafeTensors::f32(const std::string& name) const {
  const TensorInfo& t = info(name);
  const std::uint8_t* p = raw(name);
  const std::size_t n = static_cast<std::size_t>(t.numel());
  std::vector<float> out(n);
  switch (t.dtype) {
    case DType::F32:
      if (n) std::memcpy(out.data(), p, n * sizeof(float));
      break;
    case DType::F16:
    case DType::BF16:
      for (std::size_t i = 0; i < n; ++i) {
        std::uint16_t bits;
        std::memcpy(&bits, p + 2 * i, 2);
        out[i] = t.dtype == DType::F16 ? f16_to_f32(bits) : bf16_to_f32(bits);
      }
      break;
    default:
      fail("tensor " + quote_name(name) + " has dtype " + dtype_name(t.dtype) +
           ", expected a float type (F32, F16 or BF16)");
  }
  return out;
}

std::vector<std::int64_t> SafeTensors::i64(const std::string& name) const {
  const TensorInfo& t = info(name);
  const std::uint8_t* p = raw(name);
  const std::size_t n = static_cast<std::size_t>(t.numel());
  std::vector<std::int64_t> out(n);
  switch (t.dtype) {
    case DType::I64:
      if (n) std::memcpy(out.data(), p, n * sizeof(std::int64_t));
      break;
    case DType::I32:
      for (std::size_t i = 0; i < n; ++i) {
        std::int32_t v;
        std::memcpy(&v, p + 4 * i, 4);
        out[i] = v;
      }
      break;
    default:
      fail("tensor " + quote_name(name) + " has dtype " + dtype_name(t.dtype) +
           ", expected an integer type (I64 or I32)");
  }
  return out;
}

// ---------------------------------------------------------------- Writer

namespace {

[[noreturn]] void writer_fail(const std::string& problem) {
  throw Error("safetensors writer: " + problem);
}

std::string checked_quote(const std::string& s, const char* what) {
  try {
    return json::quote(s);
  } catch (const json::Error&) {
    writer_fail(std::string(what) + " " + quote_name(s) + " is not valid UTF-8");
  }
}

}  // namespace

void Writer::set_metadata(const std::string& key, const std::string& value) {
  checked_quote(key, "metadata key");
  checked_quote(value, "metadata value");
  metadata_[key] = value;
}

void Writer::add(const std::string& name, DType dtype, std::vector<std::int64_t> shape,
                 const void* data) {
  const std::string label = "tensor " + quote_name(name);
  if (name.empty()) writer_fail("empty tensor name");
  if (name == "__metadata__") writer_fail("'__metadata__' is reserved and cannot name a tensor");
  if (starts_with(name, kPaddingPrefix)) {
    writer_fail(label + ": names starting with '" + kPaddingPrefix + "' are reserved for padding");
  }
  checked_quote(name, "tensor name");
  if (names_.count(name)) writer_fail(label + " added twice");
  if (shape.size() > kMaxRank) {
    writer_fail(label + ": rank " + std::to_string(shape.size()) + " exceeds the maximum of " +
                std::to_string(kMaxRank));
  }
  for (std::int64_t d : shape) {
    if (d < 0) writer_fail(label + ": negative dimension in shape " + shape_str(shape));
  }
  std::uint64_t nbytes = 0;
  if (!checked_nbytes(shape, dtype, &nbytes)) {
    writer_fail(label + ": shape " + shape_str(shape) + " is too large");
  }
  if (nbytes > 0 && !data) writer_fail(label + ": no data given");

  TensorInfo t;
  t.name = name;
  t.dtype = dtype;
  t.shape = std::move(shape);
  t.begin = data_.size();
  t.end = t.begin + nbytes;
  const auto* src = static_cast<const std::uint8_t*>(data);
  data_.insert(data_.end(), src, src + nbytes);
  names_.insert(name);
  tensors_.push_back(std::move(t));
}

void Writer::add_f32(const std::string& name, std::vector<std::int64_t> shape, const float* data) {
  add(name, DType::F32, std::move(shape), data);
}

void Writer::add_i64(const std::string& name, std::vector<std::int64_t> shape,
                     const std::int64_t* data) {
  add(name, DType::I64, std::move(shape), data);
}

std::string Writer::header() const {
  std::string h = "{";
  bool first = true;
  if (!metadata_.empty()) {
    h += "\"__metadata__\":{";
    for (auto it = metadata_.begin(); it != metadata_.end(); ++it) {
      if (it != metadata_.begin()) h += ',';
      h += json::quote(it->first) + ":" + json::quote(it->second);
    }
    h += "}";
    first = false;
  }
  for (const TensorInfo& t : tensors_) {
    if (!first) h += ',';
    first = false;
    h += json::quote(t.name) + ":{\"dtype\":\"" + dtype_name(t.dtype) + "\",\"shape\":[";
    for (std::size_t i = 0; i < t.shape.size(); ++i) {
      if (i) h += ',';
      h += std::to_string(t.shape[i]);
    }
    h += "],\"data_offsets\":[" + std::to_string(t.begin) + "," + std::to_string(t.end) + "]}";
  }
  h += "}";
  // Spaces are JSON whitespace, so padding keeps the header valid while the data
  // section starts 64-byte aligned (as readers that map the file prefer).
  std::size_t misalign = (8 + h.size()) % 64;
  if (misalign) h.append(64 - misalign, ' ');
  return h;
}

std::vector<std::uint8_t> Writer::bytes() const {
  std::string h = header();
  std::vector<std::uint8_t> out(8 + h.size() + data_.size());
  std::uint64_t n = h.size();
  for (int i = 0; i < 8; ++i) out[i] = static_cast<std::uint8_t>(n >> (8 * i));
  std::memcpy(out.data() + 8, h.data(), h.size());
  if (!data_.empty()) std::memcpy(out.data() + 8 + h.size(), data_.data(), data_.size());
  return out;
}

void Writer::write(const std::string& path, const TemporaryFileHooks* hooks) const {
  std::string h = header();
  std::uint8_t len[8];
  std::uint64_t n = h.size();
  for (int i = 0; i < 8; ++i) len[i] = static_cast<std::uint8_t>(n >> (8 * i));
  std::string problem =
      write_file_atomically(path, {{len, 8}, {h.data(), h.size()}, {data_.data(), data_.size()}}, hooks);
  if (!problem.empty()) throw Error(path + ": " + problem);
}

}  // namespace weights
