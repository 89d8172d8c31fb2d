// Intermediate activations of a forward pass under PyTorch's module names (issue 16).
//
// A model holds a DumpSink pointer, null by default. At each boundary where a tensor
// with a PyTorch counterpart exists it calls dump_nhwc()/dump_flat(); with a null sink
// that is one pointer test and nothing else (no string, no copy, no allocation), so
// forward() still allocates nothing when dumps are off. With a sink set, converting
// NHWC to PyTorch's layout happens here, into the sink's own buffer (which may grow:
// allocating while dumping is allowed).
//
// Names follow the dump contract (docs/NUMERICS.md): the qualified name from
// named_modules(), `#k` for the k-th repeated call of one module, `[i]` / `[key]` for
// elements of tuple / dict outputs. `covers` lists the PyTorch modules a tensor stands
// for where the engine fused them (empty when the tensor is one module's output).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "nn/tensor.h"

namespace nn {

class DumpSink {
 public:
  virtual ~DumpSink() = default;
  // False for names the receiver filters out; the model then skips the conversion.
  virtual bool wants(const std::string& name) const = 0;
  // `data` holds numel(shape) floats, contiguous, in PyTorch's layout `shape`; valid
  // only during the call.
  virtual void tensor(const std::string& name, const std::vector<std::int64_t>& shape, const float* data,
                      const std::string& covers) = 0;
  // Conversion space owned by the sink, grown on demand.
  float* scratch(std::size_t floats) {
    if (scratch_.size() < floats) scratch_.resize(floats);
    return scratch_.data();
  }

 private:
  std::vector<float> scratch_;
};

// An NHWC activation as PyTorch's NCHW tensor [n, c, h, w].
void dump_nhwc(DumpSink* sink, const std::string& name, const ConstTensorView& v, const std::string& covers = "");
// An NHWC activation as PyTorch's channels-last tensor [n, h, w, c] (inside ConvNeXt's
// permuted MLP): the bytes as they are.
void dump_nhwc_as_nhwc(DumpSink* sink, const std::string& name, const ConstTensorView& v,
                       const std::string& covers = "");
// Data already in PyTorch's layout.
void dump_flat(DumpSink* sink, const std::string& name, const std::vector<std::int64_t>& shape, const float* data,
               const std::string& covers = "");

// Channels [c0, c0 + k) of an NHWC activation with `ld` floats per pixel (a fused
// product's slice) as NCHW [n, k, h, w]; v.shape.c is ignored.
void dump_nhwc_channels(DumpSink* sink, const std::string& name, const float* data, Shape s, int ld, int c0,
                        int k, const std::string& covers = "");
// Columns [c0, c0 + k) of `rows` rows with stride ld as [rows, k] (a Linear's output).
void dump_rows(DumpSink* sink, const std::string& name, const float* data, int rows, int ld, int c0, int k,
               const std::string& covers = "");

// "a.b, a.c" style lists of modules: prefix + each suffix, comma-separated.
std::string module_list(const std::string& prefix, const std::vector<std::string>& suffixes);

}  // namespace nn
