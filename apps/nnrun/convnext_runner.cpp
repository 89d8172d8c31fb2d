// nnrun --model convnext_tiny|convnext_small|convnext_base|convnext:
// input `input` [N,3,H,W] -> output `features` [N,C,H/32,W/32] (NCHW), exactly
// torchvision's model.features(input).
#include <cstdio>

#include "apps/nnrun/runner.h"
#include "nn/error.h"
#include "nn/layout.h"
#include "nn/models/convnext.h"
#include "weights/tensor_spec.h"

namespace nnrun {
namespace {

class ConvNeXtRunner : public Runner {
 public:
  ConvNeXtRunner(const std::string& name, const weights::SafeTensors& w, nn::Precision precision)
      : model_(w, "features.", precision) {
    const nn::ConvNeXtConfig& cfg = model_.config();
    const nn::ConvNeXtConfig want = named_convnext_config(name);
    if (!want.dims.empty() && !(cfg == want))
      throw weights::Error(w.source() + ": holds a ConvNeXt with " + cfg.describe() + ", not " +
                           name + " (" + want.describe() + "); use --model convnext for any configuration");
    for (const auto& s : nn::convnext_tensor_specs(cfg, "features.")) used_.push_back(s.name);
  }

  std::vector<std::string> used_tensors() const override { return used_; }

  std::string describe() const override {
    char buf[200];
    std::snprintf(buf, sizeof buf, "ConvNeXt %s, %s, packed weights %.1f MB",
                  model_.config().describe().c_str(), nn::precision_name(model_.precision()),
                  model_.weight_bytes() / 1e6);
    return buf;
  }

  void prepare(const weights::SafeTensors& in) override {
    const ConvNeXtInput x = convnext_input(in);
    input_ = in.f32("input");
    model_.plan(x.n, x.h, x.w);
    out_.resize(model_.output_shape().count());
  }

  void forward() override {
    nn::ConstTensorView y = model_.forward(input_.data());
    nn::nhwc_to_nchw(y.data, y.shape.n, y.shape.c, y.shape.h, y.shape.w, out_.data());
  }

  void write_outputs(weights::Writer& out) const override {
    const nn::Shape s = model_.output_shape();
    out.add_f32("features", {s.n, s.c, s.h, s.w}, out_.data());
  }

  nn::Profiler* profiler() override { return &model_.profiler(); }
  void set_dump(nn::DumpSink* dump) override { model_.set_dump(dump); }
  std::string dump_path() const override { return model_.dump_path(); }

 private:
  nn::ConvNeXt model_;
  std::vector<std::string> used_;
  std::vector<float> input_, out_;
};

}  // namespace

nn::ConvNeXtConfig named_convnext_config(const std::string& name) {
  if (name == "convnext_tiny") return nn::convnext_tiny_config();
  if (name == "convnext_small") return nn::convnext_small_config();
  if (name == "convnext_base") return nn::convnext_base_config();
  return {};
}

ConvNeXtInput convnext_input(const weights::SafeTensors& in) {
  if (!in.has("input")) throw weights::Error(in.source() + ": missing tensor 'input' [N,3,H,W]");
  const auto& info = in.info("input");
  if (info.shape.size() != 4)
    throw weights::Error(in.source() + ": tensor 'input' has rank " + std::to_string(info.shape.size()) +
                         ", expected 4 ([N,3,H,W])");
  if (info.shape[1] != 3)
    throw weights::Error(in.source() + ": tensor 'input' has " + std::to_string(info.shape[1]) +
                         " channels, expected 3 ([N,3,H,W])");
  for (auto d : info.shape)
    if (d > 1000000) throw weights::Error(in.source() + ": tensor 'input' is implausibly large");
  const ConvNeXtInput x{static_cast<int>(info.shape[0]), static_cast<int>(info.shape[2]),
                        static_cast<int>(info.shape[3])};
  if (x.n < 1) throw weights::Error(in.source() + ": tensor 'input' has batch size 0");
  if (x.h < 32 || x.w < 32)
    throw weights::Error(in.source() + ": tensor 'input' is " + std::to_string(x.h) + "x" + std::to_string(x.w) +
                         ", smaller than the minimum 32x32");
  // NaN/Inf in the input would give an all-NaN output and exit 0: refused, naming
  // the file and the first bad element.
  weights::check_tensors(in, {{"input", info.shape}});
  return x;
}

std::unique_ptr<Runner> make_convnext(const std::string& name, const weights::SafeTensors& w,
                                      const RunOptions& options) {
  return std::make_unique<ConvNeXtRunner>(name, w, options.precision);
}

}  // namespace nnrun
