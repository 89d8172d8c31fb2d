#include "apps/shle/synth_writer.h"

#include <cstdio>
#include <cstring>
#include <filesystem>

#include "apps/common/image_io.h"
#include "apps/common/output_files.h"
#include "shle/labelme.h"
#include "weights/json.h"

namespace shleapp {
namespace {

namespace fs = std::filesystem;

std::string num(double v, const char* f = "%.6f") {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

}  // namespace

void write_synth_scene(const shle::synth::Scene& scene, const std::string& dir, SynthLayout layout,
                       const std::function<void(int, int)>& progress) {
  const shle::synth::SceneSpec& spec = scene.spec();
  const fs::path root(dir);
  const bool released = layout == SynthLayout::Released;
  const fs::path img_dir = root / (released ? "left_colorimages" : "left");
  const fs::path disp_dir = root / (released ? "disparity_images" : "disparity");
  fs::create_directories(img_dir);
  fs::create_directories(disp_dir);

  // Each frame's files (image, LabelMe, disparity) are one set, written as temporaries
  // and then renamed; calib.json, truth.json and detections.csv come last, together,
  // so a sequence with truth.json is complete.
  shle::Calibration cal = scene.calibration();
  const std::string calib_json = (
             "{\"fx\": " + num(cal.intrinsics.fx, "%.10g") + ", \"fy\": " + num(cal.intrinsics.fy, "%.10g") +
                 ", \"cx\": " + num(cal.intrinsics.cx, "%.10g") + ", \"cy\": " + num(cal.intrinsics.cy, "%.10g") +
                 ", \"bf\": " + num(cal.bf, "%.10g") + ", \"mount_height\": " + num(cal.mount_height, "%.10g") +
                 ", \"disparity_scale\": 32, \"width\": " + std::to_string(cal.width) +
                 ", \"height\": " + std::to_string(cal.height) + "}\n");

  std::string truth = "{\n  \"device\": \"" + std::string(shle::synth::device_name(spec.device)) +
                      "\",\n  \"height\": " + num(spec.clearance, "%.10g") + ",\n  \"seed\": " +
                      std::to_string(spec.seed) + ",\n  \"frames\": [";
  std::string dets = "frame,x0,y0,x1,y1,score\n";
  const int n = scene.frame_count();
  for (int k = 0; k < n; ++k) {
    shle::synth::Frame f = scene.render(k);
    char stem[128];
    if (released)
      std::snprintf(stem, sizeof stem, "left_%llu_%06d_%d_%06d", static_cast<unsigned long long>(spec.seed), k,
                    1672000000 + k / 10, (k % 10) * 100000);
    else
      std::snprintf(stem, sizeof stem, "%06d", k);
    const std::string image_name = std::string(stem) + ".png";
    outputs::FileSet set;
    set.add((img_dir / image_name).string(), imageio::encode_png(f.image.rgb.data(), f.image.width, f.image.height, 3));
    std::vector<shle::Box> boxes;
    if (f.visible) boxes.push_back(f.box);
    set.add((img_dir / (std::string(stem) + ".json")).string(),
            shle::labelme_json(image_name, f.image.width, f.image.height, boxes));
    const std::size_t N = f.disparity.size();
    if (layout == SynthLayout::PlainPfm) {
      std::string header = "Pf\n" + std::to_string(f.image.width) + " " + std::to_string(f.image.height) + "\n-1\n";
      std::vector<std::uint8_t> bytes(header.begin(), header.end());
      for (int row = f.image.height - 1; row >= 0; --row)
        for (int x = 0; x < f.image.width; ++x) {
          float d = f.disparity[static_cast<std::size_t>(row) * f.image.width + x] / 32.0f;
          std::uint8_t b[4];
          std::memcpy(b, &d, 4);  // little-endian host (checked by weights/safetensors.h)
          bytes.insert(bytes.end(), b, b + 4);
        }
      set.add((disp_dir / (std::string(stem) + ".pfm")).string(), bytes);
    } else {
      std::vector<std::uint8_t> bytes(2 * N);
      for (std::size_t i = 0; i < N; ++i) {
        bytes[2 * i] = static_cast<std::uint8_t>(f.disparity[i] & 0xFF);
        bytes[2 * i + 1] = static_cast<std::uint8_t>(f.disparity[i] >> 8);
      }
      std::string name = released ? "disparity_5" + std::string(stem).substr(std::strlen("left")) + ".dat"
                                  : std::string(stem) + ".dat";
      set.add((disp_dir / name).string(), bytes);
    }
    set.commit();
    for (const shle::Candidate& c : f.detections)
      dets += std::to_string(k) + "," + num(c.box.x0, "%.2f") + "," + num(c.box.y0, "%.2f") + "," +
              num(c.box.x1, "%.2f") + "," + num(c.box.y1, "%.2f") + "," + num(c.score, "%.4f") + "\n";
    truth += std::string(k ? ",\n" : "\n") + "    {\"frame\": " + std::to_string(k) + ", \"image\": " +
             json::quote(image_name) + ", \"distance\": " + num(f.distance) + ", \"pitch_deg\": " +
             num(f.pitch_deg) + ", \"camera_height\": " + num(f.camera_height) +
             ", \"visible\": " + (f.visible ? "true" : "false");
    if (f.visible)
      truth += ", \"box\": [" + num(f.box.x0, "%.1f") + ", " + num(f.box.y0, "%.1f") + ", " + num(f.box.x1, "%.1f") +
               ", " + num(f.box.y1, "%.1f") + "]";
    truth += "}";
    if (progress) progress(k + 1, n);
  }
  truth += "\n  ]\n}\n";
  outputs::FileSet last;
  last.add((root / "calib.json").string(), calib_json);
  last.add((root / "truth.json").string(), truth);
  last.add((root / "detections.csv").string(), dets);
  last.commit();
}

void write_smartereye_params(const shle::Calibration& cal, const std::string& dir) {
  auto array = [](std::vector<double> v) {
    std::string s = "{\"data\": [";
    for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + num(v[i], "%.17g");
    return s + "]}\n";
  };
  std::vector<double> calib(64, 0.0), depth(8, 0.0);
  calib[4] = cal.intrinsics.fx;
  calib[12] = cal.intrinsics.fy;
  calib[39] = calib[41] = cal.intrinsics.cx + 10;
  calib[40] = calib[42] = cal.intrinsics.cy;
  depth[0] = 4;
  depth[4] = 6.5;
  fs::create_directories(dir);
  outputs::FileSet set;
  set.add((fs::path(dir) / "calibData.json").string(), array(calib));
  set.add((fs::path(dir) / "DepthCalib.json").string(), array(depth));
  set.commit();
}

}  // namespace shleapp
