// roadnn_shle_*: streaming clearance height (shle::StreamEstimator), with the boxes
// from the caller or from a Faster R-CNN session of its own.
#include <cmath>

#include "api/handles.h"
#include "api/status.h"
#include "shle/detector_box_source.h"
#include "shle/stream.h"

struct roadnn_shle {
  shle::Calibration calibration;
  shle::PipelineOptions options;
  std::unique_ptr<shle::StreamEstimator> estimator;
  roadnn_session* detector = nullptr;  // owned
  double min_score = 0.3;
  // Staging reused from frame to frame.
  shle::DisparityMap disparity;
  shle::RgbImage left;
  std::string problem;
  ~roadnn_shle() { roadnn_session_free(detector); }
};

using namespace roadnn_api;

namespace {

bool finite_positive(double v) { return v > 0 && std::isfinite(v); }

void check(bool ok, const std::string& what) {
  if (!ok) fail(ROADNN_ERROR_INVALID_ARGUMENT, "roadnn_shle_params." + what);
}

void configure(roadnn_shle& h, const roadnn_shle_params& p) {
  check(p.width >= 32 && p.height >= 32 && p.width <= 16384 && p.height <= 16384,
        "width and height must be in [32, 16384]");
  check(finite_positive(p.fx) && finite_positive(p.fy), "fx and fy must be positive");
  check(std::isfinite(p.cx) && std::isfinite(p.cy), "cx and cy must be finite");
  check(finite_positive(p.bf), "bf (baseline x focal length) must be positive");
  check(std::isfinite(p.mount_height), "mount_height must be finite");
  check(p.widest_rule == 0 || p.widest_rule == 1, "widest_rule must be 0 or 1");
  check(p.min_score >= 0 && p.min_score < 1, "min_score must be in [0, 1)");
  check(p.use_kalman == 0 || p.use_kalman == 1, "use_kalman must be 0 or 1");
  check(finite_positive(p.kalman_q) && finite_positive(p.kalman_r) && finite_positive(p.kalman_p0),
        "kalman_q, kalman_r and kalman_p0 must be positive");
  check(p.max_track_frames >= 0, "max_track_frames must be >= 0");
  shle::Calibration& c = h.calibration;
  c.intrinsics = {p.fx, p.fy, p.cx, p.cy};
  c.bf = p.bf;
  c.mount_height = p.mount_height;
  c.width = p.width;
  c.height = p.height;
  shle::PipelineOptions& o = h.options;
  o.height.extend_top = p.extend_top;
  o.height.extend_bottom = p.extend_bottom;
  o.height.min_height = p.min_height;
  o.height.bandwidth = p.bandwidth;
  o.height.sigma = p.sigma;
  o.height.lowest_n = p.lowest_n;
  o.box_rule.rule = p.widest_rule ? shle::BoxRule::Widest : shle::BoxRule::Paper;
  o.box_rule.min_score = p.min_score;
  o.tracker = p.tracker ? p.tracker : "ncc";
  o.max_track_frames = p.max_track_frames;
  o.temporal.use_kalman = p.use_kalman == 1;
  o.temporal.kalman.q = p.kalman_q;
  o.temporal.kalman.r = p.kalman_r;
  o.temporal.kalman.p0 = p.kalman_p0;
  h.min_score = p.min_score;
  // shle::Error for the rest (stage-2 ranges, tracker name): INVALID_ARGUMENT.
  h.estimator = std::make_unique<shle::StreamEstimator>(c, o);
}

// The caller's image, contiguous, in h.left (the estimator and detector read it).
void copy_left(roadnn_shle& h, const roadnn_image* image) {
  check_image(image, "roadnn_shle_push");
  if (image->width != h.calibration.width || image->height != h.calibration.height)
    fail(ROADNN_ERROR_INVALID_ARGUMENT, "roadnn_shle_push: the left image is " + std::to_string(image->width) + "x" +
                                            std::to_string(image->height) + " but the frames are " +
                                            std::to_string(h.calibration.width) + "x" +
                                            std::to_string(h.calibration.height));
  const std::size_t row = static_cast<std::size_t>(image->width) * 3;
  const std::size_t stride = image->stride ? image->stride : row;
  h.left.width = image->width;
  h.left.height = image->height;
  h.left.rgb.resize(row * image->height);
  for (int y = 0; y < image->height; ++y)
    std::copy(image->data + y * stride, image->data + y * stride + row, h.left.rgb.data() + y * row);
}

}  // namespace

extern "C" {

roadnn_shle_params roadnn_shle_default_params(void) {
  roadnn_shle_params p;
  const shle::Calibration c;
  const shle::PipelineOptions o;
  p.width = c.width;
  p.height = c.height;
  p.fx = p.fy = p.cx = p.cy = 0;  // required
  p.bf = c.bf;
  p.mount_height = c.mount_height;
  p.extend_top = o.height.extend_top;
  p.extend_bottom = o.height.extend_bottom;
  p.min_height = o.height.min_height;
  p.bandwidth = o.height.bandwidth;
  p.sigma = o.height.sigma;
  p.lowest_n = o.height.lowest_n;
  p.widest_rule = o.box_rule.rule == shle::BoxRule::Widest;
  p.min_score = o.box_rule.min_score;
  p.tracker = "ncc";
  p.max_track_frames = o.max_track_frames;
  p.use_kalman = o.temporal.use_kalman;
  p.kalman_q = o.temporal.kalman.q;
  p.kalman_r = o.temporal.kalman.r;
  p.kalman_p0 = o.temporal.kalman.p0;
  return p;
}

roadnn_status roadnn_shle_create(const roadnn_shle_params* params, const roadnn_model* detector, int threads,
                                 roadnn_shle** out) {
  if (out) *out = nullptr;
  return guarded(ROADNN_ERROR_INVALID_ARGUMENT, [&] {
    const char* fn = "roadnn_shle_create";
    require(out, fn, "out");
    require(params, fn, "params");
    if (threads < 0 || threads > 1024) fail(ROADNN_ERROR_INVALID_ARGUMENT, std::string(fn) + ": threads must be in [0, 1024]");
    auto h = std::make_unique<roadnn_shle>();
    configure(*h, *params);
    if (detector) {
      if (!is_detector(detector->kind))
        fail(ROADNN_ERROR_WRONG_MODEL,
             std::string(fn) + ": the detector must be a Faster R-CNN model, not " + kind_name(detector->kind));
      roadnn_session_params sp = roadnn_session_default_params();
      sp.threads = threads;
      sp.height = params->height;
      sp.width = params->width;
      if (roadnn_session_create(detector, &sp, &h->detector) != ROADNN_OK)
        fail(ROADNN_ERROR_INVALID_ARGUMENT, roadnn_last_error());
    }
    *out = h.release();
  });
}

void roadnn_shle_free(roadnn_shle* shle) { delete shle; }

roadnn_status roadnn_shle_reset(roadnn_shle* shle) {
  return guarded(ROADNN_ERROR_INVALID_ARGUMENT, [&] {
    require(shle, "roadnn_shle_reset", "shle");
    shle->estimator->reset();
  });
}

roadnn_status roadnn_shle_push(roadnn_shle* shle, const float* disparity, int width, int height,
                               const roadnn_box* boxes, size_t box_count, const roadnn_image* left,
                               roadnn_shle_frame* out) {
  return guarded(ROADNN_ERROR_INVALID_ARGUMENT, [&] {
    const char* fn = "roadnn_shle_push";
    require(shle, fn, "shle");
    require(out, fn, "out");
    require(disparity, fn, "disparity");
    roadnn_shle& h = *shle;
    if (width != h.calibration.width || height != h.calibration.height)
      fail(ROADNN_ERROR_INVALID_ARGUMENT, std::string(fn) + ": the disparity is " + std::to_string(width) + "x" +
                                              std::to_string(height) + " but the frames are " +
                                              std::to_string(h.calibration.width) + "x" +
                                              std::to_string(h.calibration.height));
    if (box_count > 0) require(boxes, fn, "boxes");
    if (box_count > 100000) fail(ROADNN_ERROR_INVALID_ARGUMENT, std::string(fn) + ": more than 100000 boxes");
    if (h.detector && box_count > 0)
      fail(ROADNN_ERROR_INVALID_ARGUMENT, std::string(fn) + ": this estimator finds its boxes with its detector; "
                                                            "pass no boxes");
    if (h.detector && !left) fail(ROADNN_ERROR_INVALID_ARGUMENT, std::string(fn) + ": the detector needs the left image");

    shle::StreamInput in;
    h.disparity.width = width;
    h.disparity.height = height;
    h.disparity.d.assign(disparity, disparity + static_cast<std::size_t>(width) * height);
    in.disparity = &h.disparity;
    if (left) {
      copy_left(h, left);
      in.image = &h.left;
    }
    if (h.detector) {
      roadnn_detections d;
      if (roadnn_detect(h.detector, left, &d) != ROADNN_OK) fail(ROADNN_ERROR_INVALID_ARGUMENT, roadnn_last_error());
      nn::detection::Detections det;
      for (std::size_t i = 0; i < d.count; ++i) {
        det.boxes.push_back({d.items[i].x1, d.items[i].y1, d.items[i].x2, d.items[i].y2});
        det.scores.push_back(d.items[i].score);
        det.labels.push_back(d.items[i].label);
      }
      in.candidates = shle::detections_to_candidates(det, {}, h.min_score);
    } else {
      for (std::size_t i = 0; i < box_count; ++i)
        in.candidates.push_back({{boxes[i].x0, boxes[i].y0, boxes[i].x1, boxes[i].y1}, boxes[i].score});
    }

    const shle::StreamFrame f = h.estimator->push(in);
    roadnn_shle_frame r;
    r.index = f.index;
    r.has_box = f.has_box;
    r.tracked = f.box_source == "tracker";
    r.box = {f.box.x0, f.box.y0, f.box.x1, f.box.y1, 0.0};
    r.has_height = f.stage2.has_height;
    r.height = f.stage2.has_height ? f.stage2.height : 0.0;
    r.has_filtered = f.has_filtered;
    r.filtered = f.filtered;
    r.has_scene_height = f.has_scene_height;
    r.scene_height = f.scene_height;
    h.problem.clear();
    for (const std::string& p : f.problems) h.problem += (h.problem.empty() ? "" : "; ") + p;
    r.problem = h.problem.c_str();
    *out = r;
  });
}

}  // extern "C"
