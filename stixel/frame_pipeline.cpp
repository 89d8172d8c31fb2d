#include "stixel/frame_pipeline.h"

#include <chrono>
#include <cmath>
#include <string>

#include "stixel/error.h"

namespace stixel {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// Everything that can be checked before the network runs.
void validate(const FrameOptions& o) {
  if (!(o.threshold >= 0.0 && o.threshold <= 1.0))
    throw Error("threshold must be in [0, 1], got " + std::to_string(o.threshold));
  if (!(o.train_focal >= 0.0) || !std::isfinite(o.train_focal))
    throw Error("train focal length must be positive (or 0 for none), got " + std::to_string(o.train_focal));
  if (o.train_focal > 0 && !o.camera) throw Error("train focal length: depth scaling needs a camera (K)");
  if (o.cluster) {
    if (!o.camera) throw Error("clustering needs a camera (K) for the 3D points");
    const ClusterOptions& c = o.cluster_options;
    if (c.axis_a < 0 || c.axis_a > 2 || c.axis_b < 0 || c.axis_b > 2 || c.axis_a == c.axis_b)
      throw Error("clustering: axes must be two different values of 0 (x), 1 (y), 2 (z), got " +
                  std::to_string(c.axis_a) + " and " + std::to_string(c.axis_b));
    if (!(c.eps > 0.0) || !std::isfinite(c.eps))
      throw Error("clustering: eps must be positive, got " + std::to_string(c.eps));
    if (c.min_samples < 1)
      throw Error("clustering: min_samples must be >= 1, got " + std::to_string(c.min_samples));
  }
  // Sizes, finiteness and an invertible K4 * T of the camera as given (the
  // network-size K derived from it is checked again below).
  if (o.camera) Projection(o.camera->K, o.camera->T, o.camera->source);
}

}  // namespace

FrameResult process_frame(Predictor& predictor, const RgbImageView& image, const FrameOptions& options) {
  validate(options);
  const ModelSettings& settings = predictor.settings();
  const int H = settings.input_height, W = settings.input_width;
  FrameResult r;

  auto t0 = Clock::now();
  r.resized = predictor.preprocess(image.data, image.width, image.height, image.stride);
  r.times.preprocess = ms_since(t0);

  t0 = Clock::now();
  predictor.run_network();
  r.times.network = ms_since(t0);

  if (options.camera) {
    const FrameCamera& cam = *options.camera;
    r.network_K = scale_intrinsics(cam.K, image.width, image.height, W, H);
    r.projection.emplace(r.network_K, cam.T, cam.source);
    if (options.train_focal > 0) r.depth_scale = camera_depth_scale(r.network_K, options.train_focal, cam.source);
  }

  t0 = Clock::now();
  r.world = predictor.extract(options.threshold, r.depth_scale);
  r.times.extraction = ms_since(t0);

  StixelWorld& world = r.world;
  world.has_context = true;
  if (options.camera) {
    world.context.has_calibration = true;
    CameraInfo& c = world.context.calibration;
    c.K = r.network_K;
    c.T = options.camera->T;
    c.width = W;
    c.height = H;
    c.channels = 3;
  }

  if (r.projection && (options.points || options.cluster)) {
    t0 = Clock::now();
    r.top_points = top_points(world, *r.projection);
    if (options.points) r.bottom_points = bottom_points(world, *r.projection);
    r.times.points = ms_since(t0);
  }
  if (options.cluster) {
    t0 = Clock::now();
    cluster_stixels(world, r.top_points, options.cluster_options);
    r.times.clustering = ms_since(t0);
  }
  return r;
}

}  // namespace stixel
