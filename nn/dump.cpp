#include "nn/dump.h"

#include "nn/layout.h"

namespace nn {

void dump_nhwc(DumpSink* sink, const std::string& name, const ConstTensorView& v, const std::string& covers) {
  if (!sink || !sink->wants(name)) return;
  const Shape s = v.shape;
  float* dst = sink->scratch(s.count());
  nhwc_to_nchw(v.data, s.n, s.c, s.h, s.w, dst);
  sink->tensor(name, {s.n, s.c, s.h, s.w}, dst, covers);
}

void dump_nhwc_as_nhwc(DumpSink* sink, const std::string& name, const ConstTensorView& v,
                       const std::string& covers) {
  if (!sink || !sink->wants(name)) return;
  const Shape s = v.shape;
  sink->tensor(name, {s.n, s.h, s.w, s.c}, v.data, covers);
}

void dump_flat(DumpSink* sink, const std::string& name, const std::vector<std::int64_t>& shape, const float* data,
               const std::string& covers) {
  if (!sink || !sink->wants(name)) return;
  sink->tensor(name, shape, data, covers);
}

void dump_nhwc_channels(DumpSink* sink, const std::string& name, const float* data, Shape s, int ld, int c0,
                        int k, const std::string& covers) {
  if (!sink || !sink->wants(name)) return;
  const std::size_t plane = static_cast<std::size_t>(s.h) * s.w;
  float* dst = sink->scratch(static_cast<std::size_t>(s.n) * k * plane);
  for (int n = 0; n < s.n; ++n)
    for (std::size_t p = 0; p < plane; ++p)
      for (int ch = 0; ch < k; ++ch)
        dst[(static_cast<std::size_t>(n) * k + ch) * plane + p] = data[(n * plane + p) * ld + c0 + ch];
  sink->tensor(name, {s.n, k, s.h, s.w}, dst, covers);
}

void dump_rows(DumpSink* sink, const std::string& name, const float* data, int rows, int ld, int c0, int k,
               const std::string& covers) {
  if (!sink || !sink->wants(name)) return;
  float* dst = sink->scratch(static_cast<std::size_t>(rows) * k);
  for (int r = 0; r < rows; ++r)
    for (int ch = 0; ch < k; ++ch)
      dst[static_cast<std::size_t>(r) * k + ch] = data[static_cast<std::size_t>(r) * ld + c0 + ch];
  sink->tensor(name, {rows, k}, dst, covers);
}

std::string module_list(const std::string& prefix, const std::vector<std::string>& suffixes) {
  std::string out;
  for (const auto& s : suffixes) out += (out.empty() ? "" : ",") + prefix + s;
  return out;
}

}  // namespace nn
