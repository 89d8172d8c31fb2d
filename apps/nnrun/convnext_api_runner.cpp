// The plain ConvNeXt runs of nnrun (no --profile) go through the public API
// (roadnn.hpp), as an embedder's program would: the API loads and validates the
// weights, the session plans the arena and owns the threads; --dump uses the session's
// dump callback. --profile needs the
// engine's per-layer profiler, which the API does not expose, and keeps the
// internal runner (convnext_runner.cpp).
#include <cstdio>

#include "apps/nnrun/runner.h"
#include "nn/models/convnext.h"
#include "roadnn/roadnn.hpp"
#include "weights/tensor_spec.h"

namespace nnrun {
namespace {

roadnn_isa api_isa(nn::Isa isa) {
  switch (isa) {
    case nn::Isa::Scalar: return ROADNN_ISA_SCALAR;
    case nn::Isa::Avx2: return ROADNN_ISA_AVX2;
    default: return ROADNN_ISA_AVX512;
  }
}

roadnn_model_params params_of(const RunOptions& options) {
  roadnn_model_params p = roadnn::Model::defaults(ROADNN_MODEL_CONVNEXT);
  p.max_isa = api_isa(options.max_isa);
  p.precision = options.precision == nn::Precision::Bf16 ? ROADNN_PRECISION_BF16 : ROADNN_PRECISION_F32;
  return p;
}

nn::ConvNeXtConfig config_of(const roadnn_model_info& info) {
  nn::ConvNeXtConfig c;
  for (int i = 0; i < 4 && info.stage_widths[i] > 0; ++i) {
    c.dims.push_back(info.stage_widths[i]);
    c.depths.push_back(info.stage_depths[i]);
  }
  return c;
}

class ConvNeXtApiRunner : public Runner {
 public:
  ConvNeXtApiRunner(const std::string& name, const std::string& path, const RunOptions& options)
      : path_(path), options_(options), model_(path, params_of(options)) {
    const roadnn_model_info info = model_.info();
    const nn::ConvNeXtConfig cfg = config_of(info);
    const nn::ConvNeXtConfig want = named_convnext_config(name);
    if (!want.dims.empty() && !(cfg == want))
      throw weights::Error(path + ": holds a ConvNeXt with " + cfg.describe() + ", not " + name + " (" +
                           want.describe() + "); use --model convnext for any configuration");
    char buf[200];
    std::snprintf(buf, sizeof buf, "ConvNeXt %s, %s, packed weights %.1f MB (through the API)",
                  cfg.describe().c_str(), nn::precision_name(options.precision), info.weight_bytes / 1e6);
    description_ = buf;
    dump_path_ = nn::ConvNeXt::dump_path_of(options.precision);
  }

  std::vector<std::string> used_tensors() const override { return {}; }
  std::vector<std::string> warnings() const override { return model_.warnings(); }
  std::string describe() const override { return description_; }

  void prepare(const weights::SafeTensors& in) override {
    const ConvNeXtInput x = convnext_input(in);
    input_ = in.f32("input");
    roadnn_session_params sp = roadnn::Session::defaults();
    sp.threads = options_.threads;
    sp.batch = x.n;
    sp.height = x.h;
    sp.width = x.w;
    session_ = std::make_unique<roadnn::Session>(model_, sp);
    shape_ = session_->convnext_output_shape();
    out_.resize(static_cast<std::size_t>(shape_[0] * shape_[1] * shape_[2] * shape_[3]));
  }

  void forward() override {
    roadnn::check(roadnn_convnext_run(session_->get(), input_.data(), input_.size(), out_.data(), out_.size()));
  }

  // Through the API's dump callback, as an embedder would.
  void set_dump(nn::DumpSink* dump) override {
    dump_ = dump;
    if (dump)
      session_->set_dump(&ConvNeXtApiRunner::on_tensor, this);
    else
      session_->set_dump(nullptr, nullptr);
  }

  // The engine object behind the session, as the API builds it (the text only).
  std::string dump_path() const override { return dump_path_; }

  void write_outputs(weights::Writer& out) const override {
    out.add_f32("features", {shape_[0], shape_[1], shape_[2], shape_[3]}, out_.data());
  }

 private:
  static void on_tensor(const char* name, const std::int64_t* shape, int rank, const float* data, const char* covers,
                        void* self) {
    nn::DumpSink* dump = static_cast<ConvNeXtApiRunner*>(self)->dump_;
    if (dump->wants(name)) dump->tensor(name, std::vector<std::int64_t>(shape, shape + rank), data, covers);
  }

  nn::DumpSink* dump_ = nullptr;
  std::string dump_path_;
  std::string path_;
  RunOptions options_;
  roadnn::Model model_;
  std::unique_ptr<roadnn::Session> session_;
  std::string description_;
  std::vector<std::int64_t> shape_;
  std::vector<float> input_, out_;
};

}  // namespace

std::unique_ptr<Runner> make_convnext_api(const std::string& name, const std::string& weights_path,
                                          const RunOptions& options) {
  return std::make_unique<ConvNeXtApiRunner>(name, weights_path, options);
}

}  // namespace nnrun
