// shle_synth: writes synthetic stereo sequences with ground truth for shle.
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include "apps/common/cli.h"
#include "apps/common/exec_env.h"
#include "apps/common/output_files.h"
#include "apps/shle/synth_writer.h"
#include "shle/error.h"
#include "shle/synth.h"

namespace {

std::string scene_folder(int index, const shle::synth::SceneSpec& s) {
  char b[96];
  std::snprintf(b, sizeof b, "scene_%02d_%s_%.2f", index + 1, shle::synth::device_name(s.device), s.clearance);
  return b;
}

}  // namespace

int main(int argc, char** argv) {
  apps::apply_exec_environment("shle_synth");
  std::string out, device = "bar", layout = "released";
  double height = 3.3, start = 70, end = 5, miss = 0.2;
  int seed = 1, frames = 60;
  bool benchmark = false, no_clutter = false, quiet = false, disparity_height = false;
  cli::Parser p("shle_synth", "--out DIR [options]",
                "Synthetic stereo benchmark for shle: a seeded, deterministic drive towards a height-limit\n"
                "device (bar, bridge or cables) rendered as left images, disparity (.dat, 1/32 px) and\n"
                "LabelMe boxes, with calib.json, truth.json and a simulated detector's detections.csv.");
  p.option("out", "DIR", "output folder (the sequence, or the benchmark root with --benchmark)", &out);
  p.option("device", "KIND", "bar (default), bridge or cable", &device);
  p.option("height", "M", "true clearance of the device, 1.6..8 m (default 3.3)", &height);
  p.option("seed", "N", "random seed (default 1)", &seed);
  p.option("frames", "N", "frames per sequence (default 60)", &frames);
  p.option("start", "M", "first distance to the device (default 70)", &start);
  p.option("end", "M", "last distance (default 5; earlier when the device leaves the image)", &end);
  p.option("miss-rate", "R", "fraction of frames the simulated detector misses (default 0.2)", &miss);
  p.option("layout", "L", "released (default: left_colorimages/ + disparity_images/*.dat), plain-dat or plain-pfm",
           &layout);
  p.flag("no-clutter", "no trees, pole or buildings", &no_clutter);
  p.flag("benchmark", "write the fixed benchmark set (docs/SHLE.md) into DIR/scene_*/ and DIR/benchmark.csv",
         &benchmark);
  p.flag("disparity-height", "write a small dataset in the released Disparity Height layout: DIR/val/images_017 "
         "(bar 2.85 m), images_018 (bar 2.2 m), images_019 (bridge 5.3 m) and DIR/adas_params/ (SmarterEye "
         "calibData.json, DepthCalib.json)",
         &disparity_height);
  p.flag("quiet", "no progress output", &quiet);
  p.required("out");
  p.parse(argc, argv);

  shleapp::SynthLayout lay;
  if (layout == "released")
    lay = shleapp::SynthLayout::Released;
  else if (layout == "plain-dat")
    lay = shleapp::SynthLayout::PlainDat;
  else if (layout == "plain-pfm")
    lay = shleapp::SynthLayout::PlainPfm;
  else
    p.fail("--layout must be released, plain-dat or plain-pfm");
  if (seed < 0) p.fail("--seed must be >= 0");

  outputs::install_interrupt_cleanup();
  try {
    std::vector<shle::synth::SceneSpec> specs;
    std::vector<std::string> dirs;
    if (benchmark && disparity_height) p.fail("--benchmark and --disparity-height are exclusive");
    if (disparity_height) {
      // The released demo scenes' ids and truths (shle.md section 2.3).
      const struct { int id; shle::synth::Device device; double height; } demo[] = {
          {17, shle::synth::Device::Bar, 2.85}, {18, shle::synth::Device::Bar, 2.2},
          {19, shle::synth::Device::Bridge, 5.3}};
      for (const auto& d : demo) {
        shle::synth::SceneSpec s;
        s.seed = static_cast<std::uint64_t>(seed) * 1000 + static_cast<std::uint64_t>(d.id);
        s.device = d.device;
        s.clearance = d.height;
        if (p.given("frames")) s.frames = frames;
        s.clutter = !no_clutter;
        specs.push_back(s);
        char name[32];
        std::snprintf(name, sizeof name, "images_%03d", d.id);
        dirs.push_back((std::filesystem::path(out) / "val" / name).string());
      }
      lay = shleapp::SynthLayout::Released;
      shleapp::write_smartereye_params(shle::synth::Scene(specs.front()).calibration(),
                                       (std::filesystem::path(out) / "adas_params").string());
    } else if (benchmark) {
      specs = shle::synth::benchmark_scenes();
      for (std::size_t i = 0; i < specs.size(); ++i) {
        if (p.given("frames")) specs[i].frames = frames;
        dirs.push_back((std::filesystem::path(out) / scene_folder(static_cast<int>(i), specs[i])).string());
      }
    } else {
      shle::synth::SceneSpec s;
      s.seed = static_cast<std::uint64_t>(seed);
      s.device = shle::synth::parse_device(device);
      s.clearance = height;
      s.frames = frames;
      s.start_distance = start;
      s.end_distance = end;
      s.miss_rate = miss;
      s.clutter = !no_clutter;
      specs.push_back(s);
      dirs.push_back(out);
    }
    std::string listing = "scene,device,height,seed,frames\n";
    for (std::size_t i = 0; i < specs.size(); ++i) {
      shle::synth::Scene scene(specs[i]);
      bool tty = !quiet && isatty(2);
      auto progress = [&](int done, int total) {
        if (tty) std::fprintf(stderr, "\rshle_synth %s: %d/%d frames", dirs[i].c_str(), done, total);
        if (tty && done == total) std::fputc('\n', stderr);
      };
      write_synth_scene(scene, dirs[i], lay, progress);
      if (!quiet) std::printf("%s: %s %.2f m, %d frames\n", dirs[i].c_str(), shle::synth::device_name(specs[i].device),
                              specs[i].clearance, scene.frame_count());
      char row[256];
      std::snprintf(row, sizeof row, "%s,%s,%.2f,%llu,%d\n", std::filesystem::path(dirs[i]).filename().c_str(),
                    shle::synth::device_name(specs[i].device), specs[i].clearance,
                    static_cast<unsigned long long>(specs[i].seed), scene.frame_count());
      listing += row;
    }
    if (benchmark) {
      std::string path = (std::filesystem::path(out) / "benchmark.csv").string();
      outputs::write_file(path, listing.data(), listing.size());
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "shle_synth: %s\n", e.what());
    return 1;
  }
}
