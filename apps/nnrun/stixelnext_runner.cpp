// nnrun --model stixelnext: input `input` [N,3,H,W] (the network input, already
// normalised as the weights expect: raw 0..255 for the authors' checkpoints) -> output
// `prediction` [N, A, 64, U] after the sigmoid, exactly what the authors' PyTorch model
// returns (A = 4 for head V4, else 3). U and a forced head variant come from the
// weights' __metadata__ as for the stixelnext program (stixel/predictor.h):
// stixelnext.columns, else W / stixelnext.stixel_width (8); stixelnext.head.
#include <cstdio>

#include "apps/nnrun/runner.h"
#include "nn/models/stixelnext.h"
#include "stixel/predictor.h"
#include "weights/tensor_spec.h"

namespace nnrun {
namespace {

class StixelNExTRunner : public Runner {
 public:
  StixelNExTRunner(const weights::SafeTensors& w, nn::Precision precision)
      : settings_(settings_of(w, precision)), model_(w, settings_.head, precision) {}

  std::vector<std::string> used_tensors() const override { return model_.used_tensors(); }

  std::string describe() const override {
    char buf[240];
    std::snprintf(buf, sizeof buf, "StixelNExT++ ConvNeXt %s, head %s, %s",
                  model_.backbone().config().describe().c_str(), nn::stixel_head_name(model_.head().variant()),
                  nn::precision_name(model_.backbone().precision()));
    return buf;
  }

  void prepare(const weights::SafeTensors& in) override {
    const ConvNeXtInput x = convnext_input(in);
    const int columns = settings_.columns > 0 ? settings_.columns : x.w / settings_.stixel_width;
    if (columns < 1)
      throw weights::Error(in.source() + ": tensor 'input' is " + std::to_string(x.w) + " wide, fewer than one column of " +
                           std::to_string(settings_.stixel_width) + " pixels (stixelnext.stixel_width)");
    input_ = in.f32("input");
    model_.plan(x.n, x.h, x.w, columns);
  }

  void forward() override { prediction_ = model_.forward(input_.data()); }

  void write_outputs(weights::Writer& out) const override {
    out.add_f32("prediction", model_.prediction_shape(), prediction_);
  }

  nn::Profiler* profiler() override { return &model_.profiler(); }
  void set_dump(nn::DumpSink* dump) override { model_.set_dump(dump); }
  std::string dump_path() const override { return model_.dump_path(); }

 private:
  static stixel::ModelSettings settings_of(const weights::SafeTensors& w, nn::Precision precision) {
    stixel::ModelSettings s = stixel::settings_from_metadata(w.metadata(), w.source());
    s.precision = precision;
    return s;
  }

  stixel::ModelSettings settings_;
  nn::StixelNExT model_;
  std::vector<float> input_;
  const float* prediction_ = nullptr;
};

}  // namespace

std::unique_ptr<Runner> make_stixelnext(const std::string&, const weights::SafeTensors& w, const RunOptions& options) {
  return std::make_unique<StixelNExTRunner>(w, options.precision);
}

}  // namespace nnrun
