// One StixelNExT++ frame from RGB pixels to a Stixel World with 3D points and
// clusters: what the stixelnext app (and later the public API) does per image.
//
//   preprocess (Predictor, resize to the network size) -> network -> K scaled to
//   the network size -> depth scale for train_focal -> extraction -> context ->
//   3D top / bottom points -> DBSCAN clustering
//
// No I/O: the caller decodes the image and writes the results. Errors are
// stixel::Error with a one-line message, thrown before the network runs when
// the image or the options are bad.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "stixel/clustering.h"
#include "stixel/predictor.h"
#include "stixel/projection.h"
#include "stixel/world.h"

namespace stixel {

// Interleaved RGB8 pixels that the caller owns: row r starts at
// data + r * stride bytes; stride >= 3 * width (padding bytes are never read).
struct RgbImageView {
  const std::uint8_t* data = nullptr;
  int width = 0, height = 0;
  std::size_t stride = 0;  // bytes from one row start to the next
};

// The camera of the image as given (its width x height), not of the network input.
struct FrameCamera {
  std::vector<float> K;  // 3x3 row-major (9 values)
  std::vector<float> T;  // 4x4 row-major [R|t] world -> camera (16 values), or empty for the identity
  std::string source = "camera";  // names the camera in error messages (e.g. the calibration file)
};

struct FrameOptions {
  double threshold = 0.36;  // keep candidates with P >= threshold, in [0, 1]
  // Focal length (px) of the training camera: depths are scaled by
  // f_camera / train_focal with f_camera from the network-size K (needs a camera).
  // 0: depths as predicted.
  double train_focal = 0;
  bool points = true;    // with a camera: 3D top and bottom points of every stixel
  bool cluster = false;  // DBSCAN on the top points (needs a camera)
  ClusterOptions cluster_options;  // eps, min_samples, the two axes of the bird's-eye plane
  std::optional<FrameCamera> camera;
};

// Wall-clock time of each stage (std::chrono::steady_clock), milliseconds.
struct FrameStageTimes {
  double preprocess = 0, network = 0, extraction = 0, points = 0, clustering = 0;
};

struct FrameResult {
  // Stixels, and the context as the app writes it: has_context; with a camera
  // also the calibration (network-size K, T as given, network width/height,
  // 3 channels) and, when clustering, the clusters. context.name and
  // calibration.img_name are left empty for the caller.
  StixelWorld world;
  // One point per stixel at (u, vT, d) and (u, vB, d), in the frame of K4 * T;
  // empty without a camera. top_points is also filled when clustering without
  // `points`.
  std::vector<Point3> top_points, bottom_points;
  bool resized = false;             // the image was resized to the network input size
  std::vector<float> network_K;     // K scaled to the network input size; empty without a camera
  double depth_scale = 1.0;         // the factor applied to every depth
  std::optional<Projection> projection;  // network_K and T, for the bird's-eye view and more 3D
  FrameStageTimes times;
};

// Runs one frame on `predictor` (its preprocessing, network and extraction
// buffers are reused: one frame at a time per predictor).
FrameResult process_frame(Predictor& predictor, const RgbImageView& image, const FrameOptions& options);

}  // namespace stixel
