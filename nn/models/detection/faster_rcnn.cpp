#include "nn/models/detection/faster_rcnn.h"

#include "nn/error.h"
#include "nn/models/detection/mobilenet_v3.h"
#include "nn/models/detection/detector_stages.h"
#include "nn/models/detection/resnet.h"

namespace nn::detection {

namespace {

const std::string kBody = "backbone.body.", kFpn = "backbone.fpn.", kRpn = "rpn.head.", kRoi = "roi_heads.";

// The specs must hold before any part reads a tensor, and a file with extra tensors
// is another architecture (e.g. a ResNet body given to a MobileNet model).
const weights::SafeTensors& checked(const weights::SafeTensors& st, FasterRcnnVariant v,
                                    std::vector<weights::TensorSpec>* specs) {
  *specs = faster_rcnn_tensor_specs(v, RoiHeads::classes_in(st, kRoi));
  for (const std::string& name : weights::check_tensors(st, *specs)) {
    const std::string tail = ".num_batches_tracked";
    if (name.size() > tail.size() && name.compare(name.size() - tail.size(), tail.size(), tail) == 0) continue;
    throw weights::Error(st.source() + ": unexpected tensor '" + name + "' for " + faster_rcnn_name(v) +
                         " (weights of another architecture?)");
  }
  return st;
}

std::unique_ptr<Backbone> make_backbone(const weights::SafeTensors& st, FasterRcnnVariant v, float eps) {
  if (v == FasterRcnnVariant::ResNet50Fpn) return std::make_unique<ResNet50Backbone>(st, kBody, eps);
  return std::make_unique<MobileNetV3Backbone>(st, kBody, eps);
}

}  // namespace

const char* faster_rcnn_name(FasterRcnnVariant v) {
  switch (v) {
    case FasterRcnnVariant::MobileNetV3LargeFpn: return "fasterrcnn_mobilenet_v3_large_fpn";
    case FasterRcnnVariant::MobileNetV3Large320Fpn: return "fasterrcnn_mobilenet_v3_large_320_fpn";
    case FasterRcnnVariant::ResNet50Fpn: return "fasterrcnn_resnet50_fpn";
  }
  return "?";
}

bool parse_faster_rcnn(const std::string& name, FasterRcnnVariant* out) {
  for (auto v : {FasterRcnnVariant::MobileNetV3LargeFpn, FasterRcnnVariant::MobileNetV3Large320Fpn,
                 FasterRcnnVariant::ResNet50Fpn})
    if (name == faster_rcnn_name(v)) {
      *out = v;
      return true;
    }
  return false;
}

static bool is_resnet(FasterRcnnVariant v) { return v == FasterRcnnVariant::ResNet50Fpn; }

static std::vector<int> fpn_inputs(FasterRcnnVariant v) {
  return is_resnet(v) ? std::vector<int>{256, 512, 1024, 2048} : std::vector<int>{160, 960};
}

FasterRcnnConfig faster_rcnn_defaults(FasterRcnnVariant v) {
  FasterRcnnConfig c;
  if (is_resnet(v)) {
    // One size per level '0'..'3', 'pool'; RPN score threshold 0.
    c.rpn.anchor_sizes = {{32}, {64}, {128}, {256}, {512}};
    return c;
  }
  const std::vector<float> sizes = {32, 64, 128, 256, 512};
  c.rpn.anchor_sizes = {sizes, sizes, sizes};  // '0', '1', 'pool'
  c.rpn.score_thresh = 0.05f;
  if (v == FasterRcnnVariant::MobileNetV3Large320Fpn) {
    c.transform.min_size = 320, c.transform.max_size = 640;
    c.rpn.pre_nms_top_n = c.rpn.post_nms_top_n = 150;
  }
  return c;
}

std::vector<weights::TensorSpec> faster_rcnn_tensor_specs(FasterRcnnVariant v, int classes) {
  std::vector<weights::TensorSpec> s =
      is_resnet(v) ? ResNet50Backbone::tensor_specs(kBody) : MobileNetV3Backbone::tensor_specs(kBody);
  auto add = [&](std::vector<weights::TensorSpec> more) { s.insert(s.end(), more.begin(), more.end()); };
  add(Fpn::tensor_specs(kFpn, fpn_inputs(v)));
  add(Rpn::tensor_specs(kRpn, is_resnet(v) ? 3 : 15));
  add(RoiHeads::tensor_specs(kRoi, classes));
  return s;
}

FasterRcnn::FasterRcnn(const weights::SafeTensors& st, FasterRcnnVariant v)
    : FasterRcnn(st, v, faster_rcnn_defaults(v)) {}

FasterRcnn::FasterRcnn(const weights::SafeTensors& st, FasterRcnnVariant v, const FasterRcnnConfig& cfg)
    : cfg_(cfg),
      backbone_(make_backbone(checked(st, v, &specs_), v, cfg.bn_eps)),
      fpn_(st, kFpn, backbone_->out_channels()),
      rpn_(st, kRpn, cfg.rpn),
      roi_heads_(st, kRoi, cfg.roi_heads) {}

void FasterRcnn::set_dump(DumpSink* sink) {
  dump_ = sink;
  attach_dump(sink);
}

void FasterRcnn::attach_dump(DumpSink* sink) { detection::attach_dump(*backbone_, fpn_, rpn_, roi_heads_, sink); }

void FasterRcnn::plan(int h, int w) {
  attach_dump(nullptr);  // the dry run below is no forward of the user's input
  sizes_ = transform_sizes(h, w, cfg_.transform);
  input_.resize({1, sizes_.padded_h, sizes_.padded_w, 3});
  normalised_.resize({1, h, w, 3});
  resized_.resize({1, sizes_.resized_h, sizes_.resized_w, 3});
  layer_profiler_.clear();
  const PyramidShapes shapes = plan_pyramid(*backbone_, fpn_, input_.cview(), &layer_profiler_);
  std::vector<Shape> ps = shapes.pyramid;
  rpn_.plan(ps, sizes_);
  ps.pop_back();  // 'pool' feeds only the RPN
  roi_heads_.plan(ps, sizes_, cfg_.rpn.post_nms_top_n, &layer_profiler_);
  pooled_.reserve(ps.size() + 1);
  reserve_results(cfg_.rpn.post_nms_top_n, cfg_.roi_heads.detections_per_img, &proposals_, &detections_);
  planned_h_ = h, planned_w_ = w;
  // Output names: IntermediateLayerGetter's dict '0'.., the FPN's '0'.., 'pool'.
  transform_name_ = "transform[0]";
  proposals_name_ = "rpn[0][0]";
  dump_names_ = PyramidDumpNames();
  for (std::size_t i = 0; i < shapes.features.size(); ++i)
    dump_names_.body.push_back("backbone.body[" + std::to_string(i) + "]");
  dump_names_.pyramid.resize(2);  // the FPN's dict, returned again as the backbone's
  for (std::size_t i = 0; i < shapes.pyramid.size(); ++i) {
    const std::string key = i + 1 < shapes.pyramid.size() ? std::to_string(i) : "pool";
    dump_names_.pyramid[0].push_back("backbone.fpn[" + key + "]");
    dump_names_.pyramid[1].push_back("backbone[" + key + "]");
  }
  attach_dump(dump_);
  profiler_.clear();
  prof_transform_ = profiler_.add("transform", "normalise+resize+pad", "", 0);
  prof_backbone_ = profiler_.add("backbone.body", "backbone", "", 0);
  prof_fpn_ = profiler_.add("backbone.fpn", "fpn", "", 0);
  prof_rpn_ = profiler_.add("rpn", "head+proposals", "", 0);
  prof_roi_ = profiler_.add("roi_heads", "roi_align+mlp+postprocess", "", 0);
}

const Detections& FasterRcnn::forward(const float* image) {
  if (planned_h_ == 0) throw Error("FasterRcnn::forward before plan()");
  {
    Profiler::Scope t(&profiler_, prof_transform_);
    transform_image(image, sizes_, cfg_.transform, normalised_.data.data(), resized_.data.data(), input_.view());
  }
  if (dump_) dump_nhwc(dump_, transform_name_, input_.cview());
  const std::vector<ConstTensorView>* pyramid =
      &run_pyramid(*backbone_, fpn_, input_.cview(), profiler_, prof_backbone_, prof_fpn_, dump_, dump_names_);
  run_rpn(rpn_, *pyramid, sizes_, profiler_, prof_rpn_, &proposals_);
  if (dump_ && dump_->wants(proposals_name_)) {
    const int n = static_cast<int>(proposals_.boxes.size());
    float* flat = dump_->scratch(4 * static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) {
      const Box& b = proposals_.boxes[i];
      flat[4 * i] = b.x1, flat[4 * i + 1] = b.y1, flat[4 * i + 2] = b.x2, flat[4 * i + 3] = b.y2;
    }
    dump_->tensor(proposals_name_, {n, 4}, flat, "");
  }
  {
    Profiler::Scope t(&profiler_, prof_roi_);
    pooled_.assign(pyramid->begin(), pyramid->end() - 1);  // 'pool' feeds only the RPN
    const Detections& det = roi_heads_.forward(pooled_, proposals_.boxes, sizes_);
    // transform.postprocess: ratios original / resized, each a float32 division.
    const float rh = static_cast<float>(sizes_.orig_h) / static_cast<float>(sizes_.resized_h);
    const float rw = static_cast<float>(sizes_.orig_w) / static_cast<float>(sizes_.resized_w);
    detections_.boxes.clear();
    for (const Box& b : det.boxes) detections_.boxes.push_back({b.x1 * rw, b.y1 * rh, b.x2 * rw, b.y2 * rh});
    detections_.scores.assign(det.scores.begin(), det.scores.end());
    detections_.labels.assign(det.labels.begin(), det.labels.end());
  }
  return detections_;
}

}  // namespace nn::detection
