// 64-byte aligned float storage with 64 bytes of slack after the end, so SIMD
// kernels may over-read a tail vector without touching unmapped memory.
#pragma once

#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <new>
#include <utility>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace nn {

constexpr std::size_t kAlign = 64;
constexpr std::size_t kHugePage = std::size_t{2} << 20;
constexpr std::size_t kHugeThreshold = std::size_t{4} << 20;

// Copies share the storage (a reference count): a model loaded once is copied into
// each session, which then shares every packed weight and allocates its own arena
// (resize() always detaches into fresh memory). So a buffer must never be written
// after it has been shared: weights are written only while loading, activations only
// after the session's own plan() resized them.
class AlignedBuffer {
 public:
  AlignedBuffer() = default;
  explicit AlignedBuffer(std::size_t count) { resize(count); }
  AlignedBuffer(const AlignedBuffer&) = default;
  AlignedBuffer& operator=(const AlignedBuffer&) = default;
  AlignedBuffer(AlignedBuffer&& o) noexcept
      : owner_(std::move(o.owner_)), data_(std::exchange(o.data_, nullptr)), size_(std::exchange(o.size_, 0)) {}
  AlignedBuffer& operator=(AlignedBuffer&& o) noexcept {
    owner_ = std::move(o.owner_);
    data_ = std::exchange(o.data_, nullptr);
    size_ = std::exchange(o.size_, 0);
    return *this;
  }

  // Discards the contents (of this handle: other copies keep theirs); new memory is
  // zero-filled (padding lanes stay finite).
  void resize(std::size_t count) {
    owner_.reset();
    data_ = nullptr;
    size_ = 0;
    if (count == 0) return;
    std::size_t bytes = (count * sizeof(float) + kAlign - 1) / kAlign * kAlign + kAlign;
    // Big buffers (packed weights, activations) go on 2 MiB boundaries with a
    // transparent-huge-page hint: first touching 4 KiB pages one fault at a time
    // costs hundreds of milliseconds per model on virtual machines.
    const bool huge = bytes >= kHugeThreshold;
    const std::size_t align = huge ? kHugePage : kAlign;
    if (huge) bytes = (bytes + kHugePage - 1) / kHugePage * kHugePage;
    float* p = static_cast<float*>(std::aligned_alloc(align, bytes));
    if (!p) throw std::bad_alloc();
    owner_ = std::shared_ptr<float>(p, [](float* q) { std::free(q); });
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    if (huge) madvise(p, bytes, MADV_HUGEPAGE);  // a hint: failure is harmless
#endif
    std::memset(p, 0, bytes);
    data_ = p;
    size_ = count;
  }
  // Whether another copy shares this storage.
  bool shared() const { return owner_.use_count() > 1; }

  float* data() { return data_; }
  const float* data() const { return data_; }
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  float& operator[](std::size_t i) { return data_[i]; }
  const float& operator[](std::size_t i) const { return data_[i]; }

 private:
  std::shared_ptr<float> owner_;
  float* data_ = nullptr;
  std::size_t size_ = 0;
};

}  // namespace nn
