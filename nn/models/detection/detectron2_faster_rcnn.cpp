#include "nn/models/detection/detectron2_faster_rcnn.h"

#include <algorithm>

#include "nn/error.h"
#include "nn/models/detection/detector_stages.h"
#include "nn/models/detection/resnet.h"

namespace nn::detection {

namespace {

const std::string kBody = "backbone.bottom_up.", kFpn = "backbone.", kRpn = "proposal_generator.rpn_head.",
                  kRoi = "roi_heads.";
constexpr WeightLayout kLayout = WeightLayout::Detectron2;

// The specs must hold before any part reads a tensor; a file with extra tensors is
// another architecture (a torchvision detector's names, say).
// pixel_mean / pixel_std: buffers that older detectron2 versions saved with the model
// ([3, 1, 1], B, G, R); v0.6 keeps them out of the checkpoint (non-persistent).
const char* const kPixelStats[2] = {"pixel_mean", "pixel_std"};

const weights::SafeTensors& checked(const weights::SafeTensors& st, std::vector<weights::TensorSpec>* specs) {
  const int classes = RoiHeads::classes_in(st, kRoi);
  if (classes < 2)
    throw weights::Error(st.source() + ": tensor '" + kRoi + "box_predictor.cls_score.weight' has 1 row, expected " +
                         "K + 1 >= 2 (K classes, then the background)");
  *specs = detectron2_faster_rcnn_tensor_specs(classes);
  std::vector<weights::TensorSpec> all = *specs;
  for (const char* name : kPixelStats)
    if (st.has(name)) all.push_back({name, {3, 1, 1}}), specs->push_back(all.back());
  for (const std::string& name : weights::check_tensors(st, all))
    throw weights::Error(st.source() + ": unexpected tensor '" + name + "' for " + kDetectron2FasterRcnnName +
                         " (weights of another architecture?)");
  return st;
}

// The configuration with the checkpoint's pixel statistics, where it has them.
Detectron2FasterRcnnConfig with_pixel_stats(const weights::SafeTensors& st, Detectron2FasterRcnnConfig cfg) {
  for (int k = 0; k < 2; ++k) {
    if (!st.has(kPixelStats[k])) continue;
    const std::vector<float> v = st.f32(kPixelStats[k]);
    for (int c = 0; c < 3 && c < static_cast<int>(v.size()); ++c) (k ? cfg.transform.std : cfg.transform.mean)[c] = v[c];
  }
  return cfg;
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
    : cfg_(with_pixel_stats(st, cfg)),
      backbone_(std::make_unique<ResNet50Backbone>(checked(st, &specs_), kBody, cfg.bn_eps, kLayout)),
      fpn_(st, kFpn, backbone_->out_channels(), kLayout),
      rpn_(st, kRpn, cfg.rpn),
      roi_heads_(st, kRoi, cfg.roi_heads) {}

void Detectron2FasterRcnn::set_dump(DumpSink* sink) {
  dump_ = sink;
  attach_dump(sink);
}

void Detectron2FasterRcnn::attach_dump(DumpSink* sink) {
  detection::attach_dump(*backbone_, fpn_, rpn_, roi_heads_, sink);
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
  reserve_results(cfg_.rpn.post_nms_top_n, cfg_.roi_heads.detections_per_img, &proposals_, &detections_);
  planned_h_ = h, planned_w_ = w;
  // The output dicts: bottom_up's res2..res5, the FPN's p2..p6.
  dump_names_ = PyramidDumpNames();
  for (std::size_t i = 0; i < shapes.features.size(); ++i)
    dump_names_.body.push_back("backbone.bottom_up[res" + std::to_string(i + 2) + "]");
  dump_names_.pyramid.resize(1);
  for (std::size_t i = 0; i < shapes.pyramid.size(); ++i)
    dump_names_.pyramid[0].push_back("backbone[p" + std::to_string(i + 2) + "]");
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
  const std::vector<ConstTensorView>* pyramid =
      &run_pyramid(*backbone_, fpn_, input_.cview(), profiler_, prof_backbone_, prof_fpn_, dump_, dump_names_);
  run_rpn(rpn_, *pyramid, sizes_, profiler_, prof_rpn_, &proposals_);
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
