// Synthetic stereo benchmark: a seeded, deterministic generator of drives towards
// a height-limit device (bar on posts, bridge edge, or cables), with ground truth,
// so that the pipeline can be measured without the original dataset.
//
// Each frame is ray cast from a level stereo camera (pitched by road bumps) and
// yields the left RGB image, the disparity in the released .dat encoding (uint16,
// 1/32 px), the true device box (bounding box of the device's pixels, as a LabelMe
// annotation would be) and the candidates of a simulated detector (jittered
// true box with misses, plus distractor boxes left, low and at the top edge).
// Disturbances: disparity noise growing with distance and with weak texture,
// dropouts and mismatches on weak texture and sky, foreground fattening at depth
// edges, sky and background behind the device, trees and a pole inside the box,
// pitch from road bumps, camera height jitter, missed detections.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "shle/calibration.h"
#include "shle/types.h"

namespace shle {
namespace synth {

enum class Device { Bar, Bridge, Cable };

const char* device_name(Device device);
// "bar" / "bridge" / "cable"; throws shle::Error otherwise.
Device parse_device(const std::string& name);

struct SceneSpec {
  std::uint64_t seed = 1;
  Device device = Device::Bar;
  double clearance = 3.3;  // true height of the device's lower edge above the road, m
  double start_distance = 70, end_distance = 5;
  int frames = 60;
  // Camera (the released dataset's geometry: bf = 240 m px for a 0.12 m baseline).
  int width = 1280, height = 720;
  double fx = 2000, fy = 2000, cx = 640, cy = 360;
  double baseline = 0.12, mount_height = 1.45;
  // Disparity noise (px, standard deviation) = near + far * Z / 70, raised on
  // weak texture.
  double noise_near = 0.03, noise_far = 0.06;
  // Road bumps: per-frame AR(1) pitch innovation and occasional bump impulses.
  double pitch_noise_deg = 0.04, bump_deg = 0.25, bump_rate = 0.08;
  double height_jitter = 0.01;  // camera height noise, m
  double miss_rate = 0.2;       // simulated detector: fraction of missed frames
  bool clutter = true;          // trees, pole inside the box, background buildings
};

struct Frame {
  RgbImage image;
  std::vector<std::uint16_t> disparity;  // raw, disparity = raw / 32
  bool visible = false;                  // enough device pixels for an annotation
  Box box;                               // true device box (valid when visible)
  std::vector<Candidate> detections;     // simulated detector output
  double distance = 0;                   // camera to the device's front face, m
  double pitch_deg = 0, camera_height = 0;
};

class Scene {
 public:
  // Throws shle::Error for an inconsistent spec.
  explicit Scene(const SceneSpec& spec);
  const SceneSpec& spec() const { return spec_; }
  int frame_count() const { return static_cast<int>(distance_.size()); }
  // Deterministic: depends only on the spec and the index.
  Frame render(int index) const;
  Calibration calibration() const;

  // A scene primitive: an axis-aligned box or the ellipsoid inscribed in one.
  // World frame: X right, Y up, Z forward, road surface Y = 0.
  struct Object {
    bool ellipsoid = false;
    double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    int material = 0;
    bool device = false;  // part of the annotated device
  };

 private:
  SceneSpec spec_;
  std::vector<double> distance_, pitch_deg_, cam_height_;
  std::vector<Object> objects_;
  double device_z_ = 100;
};

// The fixed benchmark set reported in docs/SHLE.md.
std::vector<SceneSpec> benchmark_scenes();

}  // namespace synth
}  // namespace shle
