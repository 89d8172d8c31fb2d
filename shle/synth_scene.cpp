#include <algorithm>
#include <cmath>

#include "shle/error.h"
#include "shle/synth.h"
#include "shle/synth_materials.h"
#include "shle/synth_random.h"

namespace shle {
namespace synth {
namespace {

Scene::Object box(double x0, double x1, double y0, double y1, double z0, double z1, int material,
                  bool device = false) {
  Scene::Object o;
  o.lo[0] = x0;
  o.hi[0] = x1;
  o.lo[1] = y0;
  o.hi[1] = y1;
  o.lo[2] = z0;
  o.hi[2] = z1;
  o.material = material;
  o.device = device;
  return o;
}

}  // namespace

const char* device_name(Device d) {
  switch (d) {
    case Device::Bar: return "bar";
    case Device::Bridge: return "bridge";
    case Device::Cable: return "cable";
  }
  return "?";
}

Device parse_device(const std::string& name) {
  if (name == "bar") return Device::Bar;
  if (name == "bridge") return Device::Bridge;
  if (name == "cable") return Device::Cable;
  throw Error("unknown device '" + name + "' (use bar, bridge or cable)");
}

Scene::Scene(const SceneSpec& spec) : spec_(spec) {
  const SceneSpec& s = spec_;
  if (!(s.clearance >= 1.6 && s.clearance <= 8.0)) throw Error("synthetic device height must be 1.6..8 m");
  if (!(s.start_distance > s.end_distance && s.end_distance >= 2.0 && s.start_distance <= 200))
    throw Error("synthetic drive must go from at most 200 m down to at least 2 m");
  if (s.frames < 2 || s.frames > 10000) throw Error("synthetic scene needs 2..10000 frames");
  if (s.width < 64 || s.height < 64 || s.width > 8192 || s.height > 8192)
    throw Error("synthetic image size must be 64..8192 px");
  if (!(s.fx > 0 && s.fy > 0 && s.baseline > 0 && s.mount_height > 0.5 && s.mount_height < s.clearance))
    throw Error("synthetic camera must have positive focal lengths and baseline, mounted below the device");
  if (!(s.miss_rate >= 0 && s.miss_rate < 1)) throw Error("synthetic miss rate must be in [0, 1)");
  if (!(s.noise_near >= 0 && s.noise_far >= 0 && s.pitch_noise_deg >= 0 && s.bump_deg >= 0 && s.bump_rate >= 0 &&
        s.bump_rate <= 1 && s.height_jitter >= 0))
    throw Error("synthetic noise levels must be >= 0");

  // Stop before the device's lower edge leaves the top 6 % of the image.
  const double z_min = (s.clearance - s.mount_height) * s.fy / std::max(s.cy - 0.06 * s.height, 1.0);
  const double end = std::max(s.end_distance, z_min);
  if (!(end < s.start_distance)) throw Error("synthetic device leaves the image before the drive starts");
  Stream rng(hash(s.seed, 0x7261ull));
  double pitch = 0;
  for (int k = 0; k < s.frames; ++k) {
    distance_.push_back(s.start_distance - (s.start_distance - end) * k / (s.frames - 1));
    pitch = 0.8 * pitch + s.pitch_noise_deg * rng.normal();
    if (rng.unit() < s.bump_rate) pitch += (rng.unit() < 0.5 ? -1 : 1) * s.bump_deg * rng.uniform(0.5, 1.0);
    pitch_deg_.push_back(pitch);
    cam_height_.push_back(s.mount_height + s.height_jitter * rng.normal());
  }

  const double h = s.clearance, Zd = device_z_;
  switch (s.device) {
    case Device::Bar:
      objects_.push_back(box(-5.0, 5.0, h, h + 0.35, Zd, Zd + 0.25, kStripes, true));
      objects_.push_back(box(-0.7, 0.7, h + 0.35, h + 1.0, Zd - 0.02, Zd + 0.02, kSign, true));
      // Posts stand 0.4 m beyond the bar's ends, joined by arms above its lower edge.
      objects_.push_back(box(-5.4, -5.0, h + 0.15, h + 0.35, Zd + 0.02, Zd + 0.23, kPost));
      objects_.push_back(box(5.0, 5.4, h + 0.15, h + 0.35, Zd + 0.02, Zd + 0.23, kPost));
      objects_.push_back(box(-5.65, -5.4, 0.0, h + 0.45, Zd - 0.03, Zd + 0.28, kPost));
      objects_.push_back(box(5.4, 5.65, 0.0, h + 0.45, Zd - 0.03, Zd + 0.28, kPost));
      break;
    case Device::Bridge:
      objects_.push_back(box(-45, 45, h, h + 1.4, Zd, Zd + 0.6, kConcrete, true));
      objects_.push_back(box(-45, 45, h, h + 1.4, Zd + 0.6, Zd + 12, kConcrete));
      objects_.push_back(box(-45, 45, h + 1.4, h + 2.3, Zd + 0.1, Zd + 0.2, kRailing));
      objects_.push_back(box(-10, -7.5, 0, h, Zd + 0.6, Zd + 11.4, kConcreteDark));
      objects_.push_back(box(7.5, 10, 0, h, Zd + 0.6, Zd + 11.4, kConcreteDark));
      break;
    case Device::Cable:
      objects_.push_back(box(-35, 35, h, h + 0.08, Zd, Zd + 0.08, kCable, true));
      objects_.push_back(box(-35, 35, h + 0.7, h + 0.78, Zd, Zd + 0.08, kCable, true));
      objects_.push_back(box(-12.3, -12.0, 0, h + 1.5, Zd - 0.15, Zd + 0.15, kPost));
      objects_.push_back(box(12.0, 12.3, 0, h + 1.5, Zd - 0.15, Zd + 0.15, kPost));
      break;
  }
  if (s.clutter) {
    Stream c(hash(s.seed, 0x636cull));
    for (int i = 0; i < 6; ++i) {  // roadside trees, some of them inside the device box
      double side = i % 2 ? 1.0 : -1.0;
      double x = side * c.uniform(6.5, 15.0), z = Zd + c.uniform(-12.0, 35.0);
      double cy = c.uniform(4.5, 8.0), rx = c.uniform(1.5, 3.0), ry = c.uniform(1.6, 3.2);
      objects_.push_back(box(x - 0.2, x + 0.2, 0, cy - 0.5 * ry, z - 0.2, z + 0.2, kTrunk));
      Object crown = box(x - rx, x + rx, cy - ry, cy + ry, z - rx, z + rx, kFoliage);
      crown.ellipsoid = true;
      objects_.push_back(crown);
    }
    // A lamp post behind the device, crossing its box.
    double px = (c.unit() < 0.5 ? -1 : 1) * c.uniform(1.5, 3.5), pz = Zd + c.uniform(8.0, 20.0);
    objects_.push_back(box(px - 0.1, px + 0.1, 0, 9.0, pz - 0.1, pz + 0.1, kPost));
    objects_.push_back(box(px - 0.1, px + 1.4, 8.8, 9.0, pz - 0.1, pz + 0.1, kPost));
    for (int i = 0; i < 10; ++i) {  // buildings far behind
      double x = c.uniform(-90, 90), z = Zd + c.uniform(70, 220);
      double w = c.uniform(10, 30), ht = c.uniform(8, 30);
      objects_.push_back(box(x - 0.5 * w, x + 0.5 * w, 0, ht, z, z + 12, kFacade));
    }
  }
}

Calibration Scene::calibration() const {
  Calibration c;
  c.intrinsics = geometry::Intrinsics{spec_.fx, spec_.fy, spec_.cx, spec_.cy};
  c.bf = spec_.baseline * spec_.fx;
  c.mount_height = spec_.mount_height;
  c.disparity_scale = 32;
  c.width = spec_.width;
  c.height = spec_.height;
  return c;
}

std::vector<SceneSpec> benchmark_scenes() {
  struct Row {
    Device device;
    double height;
  };
  static const Row rows[] = {{Device::Bar, 2.2},    {Device::Bar, 2.85},   {Device::Bar, 3.3},
                             {Device::Bar, 3.7},    {Device::Bridge, 3.2}, {Device::Bridge, 3.86},
                             {Device::Bridge, 5.3}, {Device::Cable, 4.7},  {Device::Cable, 6.0},
                             {Device::Bar, 2.0}};
  std::vector<SceneSpec> out;
  std::uint64_t seed = 101;
  for (const Row& r : rows) {
    SceneSpec s;
    s.seed = seed++;
    s.device = r.device;
    s.clearance = r.height;
    out.push_back(s);
  }
  return out;
}

}  // namespace synth
}  // namespace shle
