// nnrun --model fasterrcnn_mobilenet_v3_large_fpn | fasterrcnn_mobilenet_v3_large_320_fpn | fasterrcnn_resnet50_fpn:
// input `input` [1,3,H,W] RGB in [0,1] -> `boxes` [K,4] F32, `scores` [K] F32,
// `labels` [K] I64 in original-image pixels, as torchvision's eval output.
#include "apps/nnrun/detector_runner.h"

#include <cstdio>

#include "apps/nnrun/detection_outputs.h"
#include "nn/models/detection/faster_rcnn.h"
#include "weights/tensor_spec.h"

namespace nnrun {
namespace {

namespace det = nn::detection;

det::FasterRcnnVariant variant_of(const std::string& name) {
  det::FasterRcnnVariant v;
  if (!det::parse_faster_rcnn(name, &v)) throw weights::Error("unknown detector '" + name + "'");
  return v;
}

class DetectorRunner : public Runner {
 public:
  DetectorRunner(const std::string& name, const weights::SafeTensors& w) : name_(name), model_(w, variant_of(name)) {
    for (const auto& s : model_.tensor_specs()) used_.push_back(s.name);
    // The loader already accepted these as torchvision's BatchNorm counters.
    for (const auto& n : w.names())
      if (n.size() > 20 && n.compare(n.size() - 20, 20, ".num_batches_tracked") == 0) used_.push_back(n);
  }

  std::vector<std::string> used_tensors() const override { return used_; }

  std::string describe() const override {
    char buf[200];
    const auto& c = model_.config();
    std::snprintf(buf, sizeof buf, "%s, %d classes, min/max size %d/%d, RPN top-n %d/%d", name_.c_str(),
                  model_.num_classes(), c.transform.min_size, c.transform.max_size, c.rpn.pre_nms_top_n,
                  c.rpn.post_nms_top_n);
    return buf;
  }

  void prepare(const weights::SafeTensors& in) override {
    if (!in.has("input")) throw weights::Error(in.source() + ": missing tensor 'input' [1,3,H,W]");
    const auto& s = in.info("input").shape;
    if (s.size() != 4 || s[0] != 1 || s[1] != 3)
      throw weights::Error(in.source() + ": tensor 'input' has shape " + weights::shape_str(s) +
                           ", expected [1, 3, H, W] (one RGB image in [0, 1])");
    if (s[2] > 20000 || s[3] > 20000) throw weights::Error(in.source() + ": tensor 'input' is implausibly large");
    const int h = static_cast<int>(s[2]), w = static_cast<int>(s[3]);
    if (h < 32 || w < 32)
      throw weights::Error(in.source() + ": tensor 'input' is " + std::to_string(h) + "x" + std::to_string(w) +
                           ", smaller than the minimum 32x32");
    // NaN/Inf in the input would give an all-NaN output and exit 0: refused,
    // naming the file and the first bad element.
    weights::check_tensors(in, {{"input", in.info("input").shape}});
    input_ = in.f32("input");
    model_.plan(h, w);
  }

  void forward() override { det_ = model_.forward(input_.data()); }

  bool enable_proposal_dump() override { return dump_proposals_ = true; }

  void write_outputs(weights::Writer& out) const override {
    write_detections(out, det_, "labels");
    // As torchvision's model.rpn returns them: the transformed (resized) image's pixels.
    if (dump_proposals_) write_proposals(out, model_.proposals(), "proposal_scores", model_.sizes());
  }

  nn::Profiler* profiler() override { return &model_.profiler(); }
  void set_dump(nn::DumpSink* dump) override { model_.set_dump(dump); }
  nn::Profiler* layer_profiler() override { return &model_.layer_profiler(); }

 private:
  std::string name_;
  det::FasterRcnn model_;
  std::vector<std::string> used_;
  std::vector<float> input_;
  det::Detections det_;
  bool dump_proposals_ = false;
};

}  // namespace

std::unique_ptr<Runner> make_detector(const std::string& name, const weights::SafeTensors& w,
                                      const RunOptions&) {
  return std::make_unique<DetectorRunner>(name, w);
}

}  // namespace nnrun
