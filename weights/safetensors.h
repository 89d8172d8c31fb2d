// Strict safetensors reader and writer (https://github.com/huggingface/safetensors
// format: u64 little-endian header length N, N bytes of JSON header, then the
// tensor data). The reader validates the whole file before any tensor is read:
// header bounds, JSON syntax, dtypes, shapes (overflow-checked), and that the data
// offsets tile the data section exactly (no gap, overlap, truncation or trailing
// bytes). Every error is a weights::Error "<source>: <problem>".
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <unordered_map>
#include <vector>

#include "weights/error.h"
#include "weights/file_io.h"

namespace weights {

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__,
              "safetensors data is little-endian; this code assumes a little-endian host");

enum class DType { F64, F32, F16, BF16, I64, I32, I16, I8, U8, BOOL };

// "F32", "BF16", ... as spelled in safetensors headers.
const char* dtype_name(DType dtype);
// Bytes per element.
std::size_t dtype_size(DType dtype);
// True for the types f32() accepts: F32, F16, BF16.
bool is_float_dtype(DType dtype);

// Widens IEEE half / bfloat16 bit patterns to float exactly (subnormals, Inf and
// NaN payloads included).
float f16_to_f32(std::uint16_t bits);
float bf16_to_f32(std::uint16_t bits);

// "[96, 3, 4, 4]"; "[]" for a scalar.
std::string shape_str(const std::vector<std::int64_t>& shape);

struct TensorInfo {
  std::string name;
  DType dtype = DType::F32;
  std::vector<std::int64_t> shape;  // empty for a rank-0 scalar
  // Byte range relative to the start of the data section (as in the header).
  std::uint64_t begin = 0, end = 0;
  std::int64_t numel() const;
};

// Tensors whose name starts with this are alignment padding (U8): validated as
// part of the data layout, otherwise invisible (has/info/names/check_tensors).
constexpr const char* kPaddingPrefix = "__pad__";
// Upper bound on the JSON header, as in the reference implementation.
constexpr std::uint64_t kMaxHeaderBytes = 100000000;
constexpr std::size_t kMaxRank = 8;

class SafeTensors {
 public:
  // Reads the whole file and validates it; errors start with `path`.
  static SafeTensors load(const std::string& path);
  // Validates an in-memory file; `source` names it in errors.
  static SafeTensors from_bytes(std::vector<std::uint8_t> bytes, const std::string& source);
  // Copies are cheap: they share the (immutable) file bytes.

  const std::string& source() const { return source_; }
  // The __metadata__ object (string -> string only).
  const std::map<std::string, std::string>& metadata() const { return metadata_; }
  bool has(const std::string& name) const;
  // Throws Error "<source>: no tensor 'name'" if absent.
  const TensorInfo& info(const std::string& name) const;
  // Tensor names in file (data offset) order, padding excluded.
  std::vector<std::string> names() const;
  // All tensors in file order, padding excluded.
  const std::vector<TensorInfo>& tensors() const { return tensors_; }

  // Values as float: F32 copied, F16/BF16 widened exactly; other dtypes throw.
  std::vector<float> f32(const std::string& name) const;
  // Values as int64: I64 copied, I32 widened; other dtypes throw.
  std::vector<std::int64_t> i64(const std::string& name) const;
  // The tensor's bytes (info(name).end - begin of them), little-endian, with no
  // alignment guarantee: copy with memcpy, never cast to a wider type.
  const std::uint8_t* raw(const std::string& name) const;

 private:
  SafeTensors() = default;
  static SafeTensors from_buffer(FileBuffer bytes, const std::string& source);
  [[noreturn]] void fail(const std::string& problem) const;
  void parse_header(std::uint64_t header_len);

  std::string source_;
  std::shared_ptr<const FileBuffer> bytes_;
  std::size_t data_start_ = 0;
  std::map<std::string, std::string> metadata_;
  std::vector<TensorInfo> tensors_;
  std::unordered_map<std::string, std::size_t> index_;
};

// Builds a safetensors file in memory. Tensors are stored in the order added;
// metadata keys sorted. Names must be non-empty valid UTF-8, unique, and neither
// "__metadata__" nor start with "__pad__".
class Writer {
 public:
  void set_metadata(const std::string& key, const std::string& value);
  // `data` holds numel(shape) elements of `dtype`, little-endian.
  void add(const std::string& name, DType dtype, std::vector<std::int64_t> shape, const void* data);
  void add_f32(const std::string& name, std::vector<std::int64_t> shape, const float* data);
  void add_i64(const std::string& name, std::vector<std::int64_t> shape, const std::int64_t* data);

  // The complete file; the header is padded with spaces so the data section
  // starts at a multiple of 64 bytes.
  std::vector<std::uint8_t> bytes() const;
  // Writes via a temporary file in the same directory and a rename: never leaves
  // a partial file. Throws Error "<path>: <problem>" on I/O failure. `hooks` tell
  // the caller the temporary's name (weights/file_io.h), e.g. to remove it when
  // the program is interrupted.
  void write(const std::string& path, const TemporaryFileHooks* hooks = nullptr) const;

 private:
  std::string header() const;

  std::map<std::string, std::string> metadata_;
  std::vector<TensorInfo> tensors_;
  std::set<std::string> names_;
  std::vector<std::uint8_t> data_;
};

}  // namespace weights
