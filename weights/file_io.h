// Whole-file reads with a size limit and all-or-nothing writes, shared by the
// JSON and safetensors code. Problems come back as text so each caller can wrap
// them in its own error type with the path in front.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

namespace weights {

// Bytes of a whole file. Large buffers (Linux) come from an anonymous mapping
// advised to use transparent huge pages: on virtual machines, faulting in a
// 100 MB weights file 4 KiB at a time costs far more than reading it (measured
// 0.8 s versus 20 ms). Elsewhere, and for small files, a plain vector.
class FileBuffer {
 public:
  FileBuffer() = default;
  // Adopts the vector's storage without copying.
  explicit FileBuffer(std::vector<std::uint8_t> bytes);
  // `size` bytes of unspecified content (zero for mapped memory).
  static FileBuffer uninitialized(std::size_t size);

  FileBuffer(FileBuffer&& other) noexcept;
  FileBuffer& operator=(FileBuffer&& other) noexcept;
  FileBuffer(const FileBuffer&) = delete;
  FileBuffer& operator=(const FileBuffer&) = delete;
  ~FileBuffer();

  std::uint8_t* data() { return data_; }
  const std::uint8_t* data() const { return data_; }
  std::size_t size() const { return size_; }
  // Shrinks the logical size (the memory stays until destruction).
  void truncate(std::size_t size);

 private:
  void release() noexcept;

  std::vector<std::uint8_t> vec_;
  std::uint8_t* data_ = nullptr;  // vec_.data() or the mapping
  std::size_t size_ = 0;
  std::size_t mapped_bytes_ = 0;  // non-zero when data_ is a mapping
};

// Opens a regular file for reading without ever blocking: FIFOs, devices and
// sockets are refused ("is a pipe (FIFO), expected a regular file"), since a
// FIFO without a writer would hang open() and a device may never end. Returns
// the stream and its size, or nullptr with the problem (without the path).
std::FILE* open_regular_file(const std::string& path, std::uint64_t* size, std::string* problem);

// Reads the whole regular file into *out. Returns "" on success, otherwise the
// problem without the path, e.g. "cannot open (No such file or directory)" or
// "file is larger than the limit of 67108864 bytes". The limit is enforced while
// reading too, not only from the reported size (the file may grow).
std::string read_file(const std::string& path, std::uint64_t max_bytes, FileBuffer* out);

struct ByteSpan {
  const void* data;
  std::size_t size;
};

// Lets a caller know which temporary file a write uses, so that it can remove the
// file should the process be interrupted (the library installs no signal handlers
// and keeps no list of its own). `creating(name)` runs before the temporary is
// created, so no moment exists in which the file is there and the caller does not
// know it; `released(name)` once the name needs no removing any more: after the
// rename, after a failed creation, or after the file was removed on failure.
// Either may be empty. Exceptions they throw propagate (after cleaning up).
struct TemporaryFileHooks {
  std::function<void(const std::string& temporary)> creating;
  std::function<void(const std::string& temporary)> released;
};

// Writes the concatenated pieces to a new temporary file beside `path` (same folder,
// so a rename replaces `path` in one step), flushed to disk, and stores its name in
// *temporary. Returns "" on success, otherwise the problem (without the path) and
// the temporary is removed. On success the caller owns the temporary: it renames or
// removes it, then calls hooks->released itself.
std::string write_temporary_file(const std::string& path, const std::vector<ByteSpan>& pieces,
                                 std::string* temporary, const TemporaryFileHooks* hooks = nullptr);

// write_temporary_file, then a rename over `path`, so readers see either the old
// file or the complete new one. Returns "" on success, otherwise the problem
// (without the path); on failure the temporary file is removed.
std::string write_file_atomically(const std::string& path, const std::vector<ByteSpan>& pieces,
                                  const TemporaryFileHooks* hooks = nullptr);

}  // namespace weights
