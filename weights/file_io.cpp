#include "weights/file_io.h"

#include <algorithm>
#include <chrono>
#include <functional>
#include <thread>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <new>
#include <system_error>

#ifdef __unix__
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#endif
#ifdef __linux__
#include <sys/mman.h>
#endif

namespace weights {
namespace {

std::string errno_text(int err) { return std::generic_category().message(err); }

struct FileCloser {
  std::FILE* f;
  ~FileCloser() {
    if (f) std::fclose(f);
  }
};

// A name no other writer picks: pid, thread, the clock and the attempt number (the
// file is created exclusively, so a clash only costs another attempt). No counter:
// the library keeps no mutable global state.
std::string temporary_name(const std::string& path, unsigned attempt) {
  std::string name = path + ".tmp";
#ifdef __unix__
  name += "-" + std::to_string(static_cast<long long>(::getpid()));
#endif
  const auto tid = std::hash<std::thread::id>()(std::this_thread::get_id());
  const auto ticks = std::chrono::steady_clock::now().time_since_epoch().count();
  name += "-" + std::to_string(tid % 1000000) + "-" + std::to_string(ticks % 1000000000) + "-" + std::to_string(attempt);
  return name;
}

}  // namespace

FileBuffer::FileBuffer(std::vector<std::uint8_t> bytes)
    : vec_(std::move(bytes)), data_(vec_.data()), size_(vec_.size()) {}

FileBuffer FileBuffer::uninitialized(std::size_t size) {
  FileBuffer b;
#ifdef __linux__
  constexpr std::size_t kHugePage = 2u << 20;
  if (size >= 2 * kHugePage) {
    std::size_t bytes = (size + kHugePage - 1) / kHugePage * kHugePage;
    void* p = ::mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (p != MAP_FAILED) {
      ::madvise(p, bytes, MADV_HUGEPAGE);  // advice only: failure just means 4 KiB pages
      b.data_ = static_cast<std::uint8_t*>(p);
      b.size_ = size;
      b.mapped_bytes_ = bytes;
      return b;
    }
  }
#endif
  b.vec_.resize(size);
  b.data_ = b.vec_.data();
  b.size_ = size;
  return b;
}

FileBuffer::FileBuffer(FileBuffer&& o) noexcept
    : vec_(std::move(o.vec_)), data_(o.data_), size_(o.size_), mapped_bytes_(o.mapped_bytes_) {
  o.data_ = nullptr;
  o.size_ = 0;
  o.mapped_bytes_ = 0;
}

FileBuffer& FileBuffer::operator=(FileBuffer&& o) noexcept {
  if (this != &o) {
    release();
    vec_ = std::move(o.vec_);
    data_ = o.data_;
    size_ = o.size_;
    mapped_bytes_ = o.mapped_bytes_;
    o.data_ = nullptr;
    o.size_ = 0;
    o.mapped_bytes_ = 0;
  }
  return *this;
}

FileBuffer::~FileBuffer() { release(); }

void FileBuffer::release() noexcept {
#ifdef __linux__
  if (mapped_bytes_) ::munmap(data_, mapped_bytes_);
#endif
  vec_ = std::vector<std::uint8_t>();
  data_ = nullptr;
  size_ = 0;
  mapped_bytes_ = 0;
}

void FileBuffer::truncate(std::size_t size) {
  if (size < size_) size_ = size;
}

namespace {

std::string read_open_file(std::FILE* f, std::uint64_t hint, std::uint64_t max_bytes,
                           FileBuffer* out) {
  // One byte beyond the expected size, so reaching end of file is seen without
  // a second buffer in the common case.
  FileBuffer buf = FileBuffer::uninitialized(static_cast<std::size_t>(hint) + 1);
  std::size_t used = 0;
  for (;;) {
    std::size_t got = std::fread(buf.data() + used, 1, buf.size() - used, f);
    used += got;
    if (used > max_bytes) {
      return "file is larger than the limit of " + std::to_string(max_bytes) + " bytes";
    }
    if (used < buf.size()) {
      if (std::ferror(f)) return "read error (" + errno_text(errno) + ")";
      if (std::feof(f)) break;
      continue;
    }
    std::uint64_t grown = std::max<std::uint64_t>(static_cast<std::uint64_t>(buf.size()) * 2, 4096);
    FileBuffer bigger = FileBuffer::uninitialized(
        static_cast<std::size_t>(std::min<std::uint64_t>(grown, max_bytes + 1)));
    std::memcpy(bigger.data(), buf.data(), used);
    buf = std::move(bigger);
  }
  buf.truncate(used);
  *out = std::move(buf);
  return "";
}

}  // namespace

std::FILE* open_regular_file(const std::string& path, std::uint64_t* size, std::string* problem) {
  *size = 0;
#ifdef __unix__
  // O_NONBLOCK so that a FIFO without a writer (or a device) cannot block us in
  // open(); the file type is checked on the open descriptor (no race with a
  // rename between a stat and the open), and only regular files are read.
  int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    int err = errno;
    *problem = err == EISDIR ? "is a directory, expected a file" : "cannot open (" + errno_text(err) + ")";
    return nullptr;
  }
  struct stat st;
  if (::fstat(fd, &st) != 0) {
    *problem = "cannot stat (" + errno_text(errno) + ")";
    ::close(fd);
    return nullptr;
  }
  if (!S_ISREG(st.st_mode)) {
    *problem = S_ISDIR(st.st_mode)    ? "is a directory, expected a file"
               : S_ISFIFO(st.st_mode) ? "is a pipe (FIFO), expected a regular file"
               : S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode) ? "is a device, expected a regular file"
                                                            : "is not a regular file";
    ::close(fd);
    return nullptr;
  }
  const int flags = ::fcntl(fd, F_GETFL);
  if (flags >= 0) ::fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
  std::FILE* f = ::fdopen(fd, "rb");
  if (!f) {
    *problem = "cannot open (" + errno_text(errno) + ")";
    ::close(fd);
    return nullptr;
  }
  *size = static_cast<std::uint64_t>(st.st_size);
  return f;
#else
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    *problem = "is a directory, expected a file";
    return nullptr;
  }
  if (!std::filesystem::is_regular_file(path, ec)) {
    *problem = ec ? "cannot open (" + ec.message() + ")" : "is not a regular file";
    return nullptr;
  }
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) *problem = "cannot open (" + errno_text(errno) + ")";
  std::uintmax_t n = std::filesystem::file_size(path, ec);
  if (!ec) *size = n;
  return f;
#endif
}

std::string read_file(const std::string& path, std::uint64_t max_bytes, FileBuffer* out) {
  *out = FileBuffer();
  std::string problem;
  // The size is only a hint for the first allocation; the read loop below is
  // what enforces the limit (the file may change while we read it).
  std::uint64_t hint = 0;
  std::FILE* f = open_regular_file(path, &hint, &problem);
  if (!f) return problem;
  FileCloser closer{f};
  if (hint > max_bytes) {
    return "file is " + std::to_string(hint) + " bytes, larger than the limit of " +
           std::to_string(max_bytes) + " bytes";
  }
  try {
    return read_open_file(f, hint, max_bytes, out);
  } catch (const std::bad_alloc&) {
    return "not enough memory to read it (" + std::to_string(hint) + " bytes)";
  }
}


std::string write_temporary_file(const std::string& path, const std::vector<ByteSpan>& pieces,
                                 std::string* temporary, const TemporaryFileHooks* hooks) {
  temporary->clear();
  auto creating = [&](const std::string& name) {
    if (hooks && hooks->creating) hooks->creating(name);
  };
  auto released = [&](const std::string& name) {
    if (hooks && hooks->released) hooks->released(name);
  };
  std::string tmp;
  std::FILE* f = nullptr;
  for (unsigned attempt = 0; attempt < 100 && !f; ++attempt) {
    tmp = temporary_name(path, attempt);
    creating(tmp);
    // "x": fail rather than reuse a name someone else is writing.
    f = std::fopen(tmp.c_str(), "wbx");
    if (!f) {
      const int err = errno;
      released(tmp);
      if (err != EEXIST) return "cannot create temporary file '" + tmp + "' (" + errno_text(err) + ")";
    }
  }
  if (!f) return "cannot create a temporary file next to it (all names taken)";

  auto fail = [&](const std::string& what, int err) {
    if (f) std::fclose(f);
    std::remove(tmp.c_str());
    released(tmp);
    return what + " (" + errno_text(err) + ")";
  };
  for (const ByteSpan& piece : pieces) {
    if (piece.size == 0) continue;
    if (std::fwrite(piece.data, 1, piece.size, f) != piece.size) return fail("write error", errno);
  }
  if (std::fflush(f) != 0) return fail("write error", errno);
#ifdef __unix__
  // Without this a crash soon after the rename could leave an empty file under
  // the final name on some file systems.
  if (::fsync(::fileno(f)) != 0) return fail("cannot flush to disk", errno);
#endif
  int closed = std::fclose(f);
  f = nullptr;
  if (closed != 0) return fail("write error", errno);
  *temporary = tmp;
  return "";
}

std::string write_file_atomically(const std::string& path, const std::vector<ByteSpan>& pieces,
                                  const TemporaryFileHooks* hooks) {
  std::string tmp;
  std::string problem = write_temporary_file(path, pieces, &tmp, hooks);
  if (!problem.empty()) return problem;
  int err = 0;
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    err = errno;
    std::remove(tmp.c_str());
  }
  if (hooks && hooks->released) hooks->released(tmp);
  if (err) return "cannot rename temporary file '" + tmp + "' into place (" + errno_text(err) + ")";
  return "";
}

}  // namespace weights
