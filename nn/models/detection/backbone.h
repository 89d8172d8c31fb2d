// What the detector needs from a backbone body: the feature maps the FPN consumes.
#pragma once

#include <memory>
#include <vector>

#include "nn/dump.h"
#include "nn/profiler.h"
#include "nn/tensor.h"

namespace nn::detection {

class Backbone {
 public:
  virtual ~Backbone() = default;
  // A copy sharing the packed weights (nn/buffer.h); call it on an unplanned body
  // only, then plan the copy.
  virtual std::unique_ptr<Backbone> clone() const = 0;
  virtual std::vector<int> out_channels() const = 0;
  // Plans every buffer for an h x w input; registers one row per layer in `layers`
  // (may be null), which forward() then times when it is enabled.
  virtual void plan(int h, int w, Profiler* layers) = 0;
  // in: {1, h, w, 3}. Views stay valid until the next forward.
  virtual const std::vector<ConstTensorView>& forward(const ConstTensorView& in) = 0;
  // Intermediate tensors of the body under torchvision's names (nn/dump.h); null: off.
  // A body without inner dumps ignores it (the detector dumps its outputs).
  virtual void set_dump(DumpSink* sink) { (void)sink; }
};

// A Backbone owner that copies by clone(), so that the detector stays copyable.
class BackboneHolder {
 public:
  BackboneHolder() = default;
  explicit BackboneHolder(std::unique_ptr<Backbone> b) : p_(std::move(b)) {}
  BackboneHolder(const BackboneHolder& o) : p_(o.p_ ? o.p_->clone() : nullptr) {}
  BackboneHolder& operator=(const BackboneHolder& o) {
    if (this != &o) p_ = o.p_ ? o.p_->clone() : nullptr;
    return *this;
  }
  BackboneHolder(BackboneHolder&&) noexcept = default;
  BackboneHolder& operator=(BackboneHolder&&) noexcept = default;
  Backbone* operator->() const { return p_.get(); }
  Backbone& operator*() const { return *p_; }
  explicit operator bool() const { return p_ != nullptr; }

 private:
  std::unique_ptr<Backbone> p_;
};

}  // namespace nn::detection
