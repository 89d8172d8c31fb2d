// roadnn_stixel_run: an RGB buffer -> Stixel World -> 3D points -> clusters.
#include <cmath>

#include "api/handles.h"
#include "api/status.h"
#include "stixel/frame_pipeline.h"

using namespace roadnn_api;

namespace {

void check_params(const roadnn_stixel_params& p, bool has_camera) {
  const char* fn = "roadnn_stixel_run";
  if (!(p.threshold >= 0 && p.threshold <= 1))
    fail(ROADNN_ERROR_INVALID_ARGUMENT, std::string(fn) + ": threshold must be in [0, 1]");
  if (!(p.train_focal >= 0) || !std::isfinite(p.train_focal))
    fail(ROADNN_ERROR_INVALID_ARGUMENT, std::string(fn) + ": train_focal must be 0 or a positive focal length");
  if (p.train_focal > 0 && !has_camera)
    fail(ROADNN_ERROR_INVALID_ARGUMENT, std::string(fn) + ": train_focal needs a camera");
  if (p.cluster != 0 && p.cluster != 1) fail(ROADNN_ERROR_INVALID_ARGUMENT, std::string(fn) + ": cluster must be 0 or 1");
  if (p.cluster && !has_camera)
    fail(ROADNN_ERROR_INVALID_ARGUMENT, std::string(fn) + ": clustering needs a camera (3D points)");
  if (p.cluster) {
    if (!(p.cluster_eps > 0) || !std::isfinite(p.cluster_eps))
      fail(ROADNN_ERROR_INVALID_ARGUMENT, std::string(fn) + ": cluster_eps must be positive");
    if (p.cluster_min_samples < 1)
      fail(ROADNN_ERROR_INVALID_ARGUMENT, std::string(fn) + ": cluster_min_samples must be >= 1");
    if (p.axis_a < 0 || p.axis_a > 2 || p.axis_b < 0 || p.axis_b > 2 || p.axis_a == p.axis_b)
      fail(ROADNN_ERROR_INVALID_ARGUMENT, std::string(fn) + ": axis_a and axis_b must be two different of 0, 1, 2");
  }
}

void copy3(const stixel::Point3& p, double out[3]) {
  out[0] = p.x, out[1] = p.y, out[2] = p.z;
}

}  // namespace

extern "C" {

roadnn_stixel_params roadnn_stixel_default_params(void) {
  roadnn_stixel_params p;
  p.threshold = 0.36;
  p.train_focal = 0;
  p.cluster = 0;
  const stixel::ClusterOptions co;
  p.cluster_eps = co.eps;
  p.cluster_min_samples = co.min_samples;
  p.axis_a = co.axis_a;
  p.axis_b = co.axis_b;
  return p;
}

roadnn_status roadnn_stixel_run(roadnn_session* session, const roadnn_image* image, const roadnn_camera* camera,
                                const roadnn_stixel_params* params, roadnn_stixel_world* out) {
  return guarded(ROADNN_ERROR_INVALID_ARGUMENT, [&] {
    const char* fn = "roadnn_stixel_run";
    require(session, fn, "session");
    require(out, fn, "out");
    require_kind(session, session->predictor != nullptr, fn, "StixelNExT++");
    const roadnn_stixel_params p = params ? *params : roadnn_stixel_default_params();
    check_params(p, camera != nullptr);
    check_image(image, fn);

    stixel::FrameOptions o;
    o.threshold = p.threshold;
    o.train_focal = p.train_focal;
    o.points = camera != nullptr;
    o.cluster = p.cluster == 1;
    o.cluster_options.eps = p.cluster_eps;
    o.cluster_options.min_samples = p.cluster_min_samples;
    o.cluster_options.axis_a = p.axis_a;
    o.cluster_options.axis_b = p.axis_b;
    if (camera) {
      stixel::FrameCamera c;
      c.K.assign(camera->K, camera->K + 9);
      if (camera->has_T) c.T.assign(camera->T, camera->T + 16);
      c.source = "roadnn_camera";
      o.camera = std::move(c);
    }
    const stixel::RgbImageView view{image->data, image->width, image->height,
                                    image->stride ? image->stride : static_cast<std::size_t>(image->width) * 3};
    nn::ExecScope scope(session->exec);
    const stixel::FrameResult r = stixel::process_frame(*session->predictor, view, o);

    auto& v = session->stixels;
    v.resize(r.world.stixels.size());
    for (std::size_t i = 0; i < v.size(); ++i) {
      const stixel::Stixel& s = r.world.stixels[i];
      roadnn_stixel& t = v[i];
      t.u = s.u, t.top = s.vT, t.bottom = s.vB, t.width = s.width;
      t.depth = s.d, t.confidence = s.confidence, t.cluster = s.cluster;
      for (int a = 0; a < 3; ++a) t.top_point[a] = t.bottom_point[a] = 0;
      if (camera) copy3(r.top_points[i], t.top_point), copy3(r.bottom_points[i], t.bottom_point);
    }
    const stixel::ModelSettings& st = session->predictor->settings();
    roadnn_stixel_world w;
    w.stixels = v.data();
    w.count = v.size();
    w.clusters = o.cluster ? r.world.context.clusters : -1;
    w.image_width = st.input_width;
    w.image_height = st.input_height;
    for (int i = 0; i < 9; ++i) w.K[i] = camera ? static_cast<double>(r.network_K[i]) : 0.0;
    w.resized = r.resized ? 1 : 0;
    *out = w;
  });
}

}  // extern "C"
