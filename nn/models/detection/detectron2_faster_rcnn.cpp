#include "nn/models/detection/detectron2_faster_rcnn.h"

#include <algorithm>

#include "nn/error.h"
#include "nn/models/detection/pyramid_plan.h"
#include "nn/models/detection/resnet.h"

namespace nn::detection {

namespace {

const std::string kBody = "backbone.bottom_up.", kFpn = "backbone.", kRpn = "proposal_generator.rpn_head.",
                  kRoi = "roi_heads.";
constexpr WeightLayout kLayout = WeightLayout::Detectron2;

// The specs must hold before any part reads a tensor; a file with extra tensors is
// another architecture (a torchvision detector's names, say).
const weights::SafeTensors& checked(const weights::SafeTensors& st, std::vector<weights::TensorSpec>* specs) {
  *specs = detectron2_faster_rcnn_tensor_specs(RoiHeads::classes_in(st, kRoi));
  for (const std::string& name : weights::check_tensors(st, *specs))
    throw weights::Error(st.source() + ": unexpected tensor '" + name + "' for " + kDetectron2FasterRcnnName +
                         " (weights of another architecture?)");
  return st;
}

}  // namespace

std::vector<weights::TensorSpec> detectron2_faster_rcnn_tensor_specs(int classes) {
  std::vector<weights::TensorSpec> s = ResNet50Backbone::tensor_specs(kBody, kLayout);
  auto add = [&](std::vector<weights::TensorSpec> more) { s.insert(s.end(), more.begin(), more.end()); };
  add(Fpn::tensor_specs(kFpn, {256, 512, 1024, 2048}, kLayout));
  add(Rpn::tensor_specs(kRpn, 3, kLayout));
  add(RoiHeads::tensor_specs(kRoi, classes, 1024, kLayout));
  return s;
}

Detectron2FasterRcnn::Detectron2FasterRcnn(const weights::SafeTensors& st, const Detectron2FasterRcnnConfig& cfg)
    : cfg_(cfg),
      backbone_(std::make_unique<ResNet50Backbone>(checked(st, &specs_), kBody, cfg.bn_eps, kLayout)),
      fpn_(st, kFpn, backbone_->out_channels(), kLayout),
      rpn_(st, kRpn, cfg.rpn),
      roi_heads_(st, kRoi, cfg.roi_heads) {}

void Detectron2FasterRcnn::set_dump(DumpSink* sink) {
  dump_ = sink;
  attach_dump(sink);
}

void Detectron2FasterRcnn::attach_dump(DumpSink* sink) {
  backbone_->set_dump(sink);
  fpn_.set_dump(sink);
  rpn_.set_dump(sink);
  roi_heads_.set_dump(sink);
}

void Detectron2FasterRcnn::plan(int h, int w) {
  attach_dump(nullptr);  // the dry run below is no forward of the user's input
  sizes_ = detectron2_sizes(h, w, cfg_.transform);
  transform_.plan(sizes_);
  input_.resize({1, sizes_.padded_h, sizes_.padded_w, 3});
  layer_profiler_.clear();
  const PyramidShapes shapes = plan_pyramid(*backbone_, fpn_, input_.cview(), &layer_profiler_);
  rpn_.plan(shapes.pyramid, sizes_);
  std::vector<Shape> pooled(shapes.pyramid.begin(), shapes.pyramid.end() - 1);  // p6 feeds only the RPN
  roi_heads_.plan(pooled, sizes_, cfg_.rpn.post_nms_top_n, &layer_profiler_);
  pooled_.reserve(shapes.pyramid.size());
  const std::size_t rois = static_cast<std::size_t>(std::max(cfg_.rpn.post_nms_top_n, 0));
  proposals_.boxes.reserve(rois);
  proposals_.scores.reserve(rois);
  const std::size_t kept = static_cast<std::size_t>(std::max(cfg_.roi_heads.detections_per_img, 0));
  detections_.boxes.reserve(kept);
  detections_.scores.reserve(kept);
  detections_.labels.reserve(kept);
  planned_h_ = h, planned_w_ = w;
  body_names_.clear(), fpn_names_.clear();
  for (std::size_t i = 0; i < shapes.features.size(); ++i) body_names_.push_back(kBody + "res" + std::to_string(i + 2));
  for (std::size_t i = 0; i < shapes.pyramid.size(); ++i) fpn_names_.push_back(kFpn + "p" + std::to_string(i + 2));
  for (auto& n : body_names_) n = "backbone.bottom_up[" + n.substr(kBody.size()) + "]";
  for (auto& n : fpn_names_) n = "backbone[" + n.substr(kFpn.size()) + "]";
  attach_dump(dump_);
  profiler_.clear();
  prof_transform_ = profiler_.add("preprocess", "Pillow resize+BGR+normalise+pad", "", 0);
  prof_backbone_ = profiler_.add("backbone.bottom_up", "backbone", "", 0);
  prof_fpn_ = profiler_.add("backbone", "fpn", "", 0);
  prof_rpn_ = profiler_.add("proposal_generator", "head+proposals", "", 0);
  prof_roi_ = profiler_.add("roi_heads", "roi_align+mlp+inference", "", 0);
  prof_post_ = profiler_.add("postprocess", "rescale+clip to the original image", "", 0);
}

const Detections& Detectron2FasterRcnn::forward(const std::uint8_t* rgb) {
  if (planned_h_ == 0) throw Error("Detectron2FasterRcnn::forward before plan()");
  {
    Profiler::Scope t(&profiler_, prof_transform_);
    transform_.run(rgb, cfg_.transform, input_.view());
  }
  if (dump_) dump_nhwc(dump_, "preprocess_image", input_.cview());
  const std::vector<ConstTensorView>* feats;
  const std::vector<ConstTensorView>* pyramid;
  {
    Profiler::Scope t(&profiler_, prof_backbone_);
    feats = &backbone_->forward(input_.cview());
  }
  if (dump_)
    for (std::size_t i = 0; i < feats->size(); ++i) dump_nhwc(dump_, body_names_[i], (*feats)[i]);
  {
    Profiler::Scope t(&profiler_, prof_fpn_);
    pyramid = &fpn_.forward(*feats);
  }
  if (dump_)
    for (std::size_t i = 0; i < pyramid->size(); ++i) dump_nhwc(dump_, fpn_names_[i], (*pyramid)[i]);
  {
    Profiler::Scope t(&profiler_, prof_rpn_);
    const Proposals& p = rpn_.forward(*pyramid, sizes_);
    proposals_.boxes.assign(p.boxes.begin(), p.boxes.end());
    proposals_.scores.assign(p.scores.begin(), p.scores.end());
  }
  const Detections* det;
  {
    Profiler::Scope t(&profiler_, prof_roi_);
    pooled_.assign(pyramid->begin(), pyramid->end() - 1);  // p6 feeds only the RPN
    det = &roi_heads_.forward(pooled_, proposals_.boxes, sizes_);
  }
  Profiler::Scope t(&profiler_, prof_post_);
  // detector_postprocess: scale factors in double, applied to the float32 boxes as
  // torch applies a Python float (rounded to float32); clip to the original image;
  // drop boxes with no width or height.
  const float sx = static_cast<float>(static_cast<double>(sizes_.orig_w) / sizes_.resized_w);
  const float sy = static_cast<float>(static_cast<double>(sizes_.orig_h) / sizes_.resized_h);
  detections_.boxes.clear(), detections_.scores.clear(), detections_.labels.clear();
  for (std::size_t i = 0; i < det->boxes.size(); ++i) {
    const Box& r = det->boxes[i];
    const Box b = clip_box({r.x1 * sx, r.y1 * sy, r.x2 * sx, r.y2 * sy}, sizes_.orig_h, sizes_.orig_w);
    if (!(b.x2 - b.x1 > 0.0f && b.y2 - b.y1 > 0.0f)) continue;
    detections_.boxes.push_back(b);
    detections_.scores.push_back(det->scores[i]);
    detections_.labels.push_back(det->labels[i]);
  }
  return detections_;
}

}  // namespace nn::detection
