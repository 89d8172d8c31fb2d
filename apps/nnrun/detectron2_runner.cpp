// nnrun --model detectron2_faster_rcnn_r50_fpn: an RGB8 image (--image FILE, or an
// input file's `input` U8 [H, W, 3]) -> `boxes` F32 [K, 4] (x1, y1, x2, y2 in the
// original image's pixels), `scores` F32 [K], `classes` I64 [K] (0-based), as
// detectron2's Instances; --dump-proposals adds the RPN's proposals.
#include "apps/nnrun/detector_runner.h"

#include <cstdio>

#include "apps/nnrun/detection_outputs.h"
#include "nn/models/detection/detectron2_faster_rcnn.h"
#include "weights/tensor_spec.h"

namespace nnrun {
namespace {

namespace det = nn::detection;

class Detectron2Runner : public Runner {
 public:
  explicit Detectron2Runner(const weights::SafeTensors& w) : model_(w) {
    for (const auto& s : model_.tensor_specs()) used_.push_back(s.name);
  }

  std::vector<std::string> used_tensors() const override { return used_; }

  std::string describe() const override {
    char buf[200];
    const auto& c = model_.config();
    std::snprintf(buf, sizeof buf, "%s, %d classes, short side %d, long side at most %d, RPN top-n %d/%d",
                  det::kDetectron2FasterRcnnName, model_.num_classes(), c.transform.min_size, c.transform.max_size,
                  c.rpn.pre_nms_top_n, c.rpn.post_nms_top_n);
    return buf;
  }

  void prepare(const weights::SafeTensors& in) override {
    if (!in.has("input")) throw weights::Error(in.source() + ": missing tensor 'input' U8 [H, W, 3]");
    const auto& info = in.info("input");
    const auto& s = info.shape;
    if (info.dtype != weights::DType::U8 || s.size() != 3 || s[2] != 3)
      throw weights::Error(in.source() + ": tensor 'input' is " + weights::dtype_name(info.dtype) + " " +
                           weights::shape_str(s) + ", expected U8 [H, W, 3] (one RGB8 image)");
    if (s[0] > 20000 || s[1] > 20000) throw weights::Error(in.source() + ": tensor 'input' is implausibly large");
    const int h = static_cast<int>(s[0]), w = static_cast<int>(s[1]);
    const std::uint8_t* p = in.raw("input");
    prepare_rgb8(p, h, w, in.source());
  }

  bool takes_image() const override { return true; }

  void prepare_rgb8(const std::uint8_t* rgb, int h, int w, const std::string& source) override {
    if (h < 32 || w < 32)
      throw weights::Error(source + ": the image is " + std::to_string(h) + "x" + std::to_string(w) +
                           ", smaller than the minimum 32x32");
    input_.assign(rgb, rgb + static_cast<std::size_t>(h) * w * 3);
    model_.plan(h, w);
  }

  void forward() override { det_ = model_.forward(input_.data()); }

  bool enable_proposal_dump() override { return dump_proposals_ = true; }

  void write_outputs(weights::Writer& out) const override {
    write_detections(out, det_, "classes");
    // As detectron2's proposal generator returns them: resized-image pixels, objectness logits.
    if (dump_proposals_) write_proposals(out, model_.proposals(), "proposal_logits", model_.sizes());
  }

  nn::Profiler* profiler() override { return &model_.profiler(); }
  void set_dump(nn::DumpSink* dump) override { model_.set_dump(dump); }
  nn::Profiler* layer_profiler() override { return &model_.layer_profiler(); }

 private:
  det::Detectron2FasterRcnn model_;
  std::vector<std::string> used_;
  std::vector<std::uint8_t> input_;
  det::Detections det_;
  bool dump_proposals_ = false;
};

}  // namespace

std::unique_ptr<Runner> make_detectron2(const std::string&, const weights::SafeTensors& w, const RunOptions&) {
  return std::make_unique<Detectron2Runner>(w);
}

}  // namespace nnrun
