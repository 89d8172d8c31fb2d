#include "nn/models/stixelnext.h"

#include "nn/error.h"
#include "nn/pool.h"

namespace nn {

namespace {

StixelHeadVariant choose_head(const weights::SafeTensors& st, std::optional<StixelHeadVariant> force, int c) {
  return force ? *force : detect_stixel_head(st, "classifier.", c);
}

}  // namespace

StixelNExT::StixelNExT(const weights::SafeTensors& st, std::optional<StixelHeadVariant> force,
                       Precision precision)
    : backbone_(st, "features.", precision),
      head_(st, "classifier.", choose_head(st, force, backbone_.out_channels()), backbone_.out_channels()) {}

std::vector<std::string> StixelNExT::used_tensors() const {
  std::vector<std::string> names;
  for (const auto& s : convnext_tensor_specs(backbone_.config(), "features.")) names.push_back(s.name);
  for (const auto& s : head_.tensor_specs()) names.push_back(s.name);
  return names;
}

void StixelNExT::set_dump(DumpSink* sink) {
  dump_ = sink;
  backbone_.set_dump(sink);
  head_.set_dump(sink);
}

void StixelNExT::plan(int n, int h, int w, int columns) {
  if (columns < 1 || columns > 100000) throw Error("stixelnext: the column count must be between 1 and 100000");
  backbone_.plan(n, h, w);
  const Shape f = backbone_.output_shape();
  const Shape p = mean_over_rows_shape(f);
  pooled_.resize(p.count());
  head_.plan(n, p.w);
  columns_ = columns;
  prediction_.resize(static_cast<std::size_t>(n) * head_.attributes() * StixelHead::kCandidates * columns);
  Profiler& prof = backbone_.profiler();
  prof_pool_ = prof.add(pool_name_, "mean over rows", "[" + std::to_string(n) + ", " + std::to_string(f.c) + ", 1, " +
                                                          std::to_string(f.w) + "]", 0);
  prof_head_ = prof.add(head_name_, std::string("stixel head ") + stixel_head_name(head_.variant()),
                        "[" + std::to_string(n) + ", " + std::to_string(head_.attributes()) + ", 64, " +
                            std::to_string(columns) + "]",
                        0);
}

std::vector<std::int64_t> StixelNExT::prediction_shape() const {
  return {backbone_.input_shape().n, head_.attributes(), StixelHead::kCandidates, columns_};
}

const float* StixelNExT::forward(const float* input_nchw) {
  if (pooled_.empty()) throw Error("stixelnext: forward() before plan()");
  ConstTensorView f = backbone_.forward(input_nchw);
  const Shape p = mean_over_rows_shape(f.shape);
  {
    Profiler::Scope t(&backbone_.profiler(), prof_pool_);
    mean_over_rows(f, TensorView{pooled_.data(), p});
  }
  if (dump_) dump_nhwc(dump_, pool_name_, ConstTensorView(pooled_.data(), p));
  {
    Profiler::Scope t(&backbone_.profiler(), prof_head_);
    head_.forward(ConstTensorView(pooled_.data(), p), columns_, prediction_.data());
  }
  if (dump_) dump_flat(dump_, head_name_, prediction_shape(), prediction_.data(), head_.output_covers());
  return prediction_.data();
}

}  // namespace nn
