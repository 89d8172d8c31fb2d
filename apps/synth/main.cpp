// synth: seeded random weights and inputs, so the demo, benchmarks and users can
// run every model without Python or a trained checkpoint. Weights follow the
// tests' scales, which make every layer matter: conv/linear N(0, 1/fan_in),
// layer scale U(0.3, 1), norm gamma N(1, 0.2), beta N(0, 0.1), biases N(0, 0.05).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <sstream>
#include <string>
#include <vector>

#include "apps/common/cli.h"
#include "apps/common/exec_env.h"
#include "apps/common/output_files.h"
#include "nn/models/convnext.h"
#include "nn/models/detection/detectron2_faster_rcnn.h"
#include "nn/models/detection/faster_rcnn.h"
#include "nn/models/stixel_head.h"
#include "nn/models/synthetic_weights.h"
#include "apps/common/image_io.h"
#include "weights/safetensors.h"

namespace {

std::vector<weights::TensorSpec> model_specs(const std::string& model, nn::StixelHeadVariant head, int classes) {
  nn::detection::FasterRcnnVariant detector;
  if (nn::detection::parse_faster_rcnn(model, &detector))
    return nn::detection::faster_rcnn_tensor_specs(detector, classes);
  // detectron2 counts foreground classes (NUM_CLASSES); cls_score has one more row.
  if (model == nn::detection::kDetectron2FasterRcnnName)
    return nn::detection::detectron2_faster_rcnn_tensor_specs(classes + 1);
  if (model == "stixelnext") {
    auto specs = nn::convnext_tensor_specs(nn::convnext_tiny_config(), "features.");
    for (auto& s : nn::stixel_head_tensor_specs(head, 768, "classifier.")) specs.push_back(s);
    return specs;
  }
  if (model == "convnext_tiny") return nn::convnext_tensor_specs(nn::convnext_tiny_config(), "features.");
  if (model == "convnext_small") return nn::convnext_tensor_specs(nn::convnext_small_config(), "features.");
  if (model == "convnext_base") return nn::convnext_tensor_specs(nn::convnext_base_config(), "features.");
  return {};
}

// A plain road scene for demos: sky, horizon, road with lane marks, a few boxy
// "vehicles" and posts, with mild texture so image codecs and the network see detail.
std::vector<std::uint8_t> road_scene(int w, int h, nn::SplitMix64& rng) {
  std::vector<std::uint8_t> px(static_cast<std::size_t>(w) * h * 3);
  const int horizon = h * 45 / 100;
  struct Box { int x0, y0, x1, y1; std::uint8_t r, g, b; };
  std::vector<Box> boxes;
  for (int i = 0; i < 6; ++i) {
    const double depth = 0.15 + 0.8 * rng.uniform();  // 0 near .. 1 far
    const int bw = static_cast<int>(w * (0.25 - 0.2 * depth)), bh = static_cast<int>(bw * (0.6 + 0.3 * rng.uniform()));
    const int bottom = horizon + static_cast<int>((h - horizon) * (1.0 - depth) * 0.9) + 4;
    const int x0 = static_cast<int>((w - bw) * rng.uniform());
    boxes.push_back({x0, bottom - bh, x0 + bw, bottom, static_cast<std::uint8_t>(40 + 200 * rng.uniform()),
                     static_cast<std::uint8_t>(40 + 150 * rng.uniform()), static_cast<std::uint8_t>(40 + 200 * rng.uniform())});
  }
  std::sort(boxes.begin(), boxes.end(), [](const Box& a, const Box& b) { return a.y1 < b.y1; });  // far first
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      double r, g, b;
      if (y < horizon) {  // sky
        const double t = static_cast<double>(y) / horizon;
        r = 110 + 80 * t, g = 160 + 60 * t, b = 230 + 20 * t;
      } else {  // road between grass verges, lane marks converging to the centre
        const double t = static_cast<double>(y - horizon) / (h - horizon);
        const double half = w * (0.05 + 0.55 * t), cx = w * 0.5;
        const bool road = std::fabs(x - cx) < half;
        r = road ? 95 : 70, g = road ? 95 : 120, b = road ? 100 : 60;
        const double lane = std::fabs(std::fabs(x - cx) - half * 0.33);
        if (road && lane < 2 + 10 * t && static_cast<int>(t * 40) % 2 == 0) r = g = b = 230;
      }
      for (const Box& bx : boxes)
        if (x >= bx.x0 && x < bx.x1 && y >= bx.y0 && y < bx.y1) {
          const bool window = y < bx.y0 + (bx.y1 - bx.y0) / 3 && x > bx.x0 + (bx.x1 - bx.x0) / 8 && x < bx.x1 - (bx.x1 - bx.x0) / 8;
          r = window ? 40 : bx.r, g = window ? 50 : bx.g, b = window ? 60 : bx.b;
        }
      const double noise = 12.0 * (rng.uniform() - 0.5);
      std::uint8_t* p = &px[(static_cast<std::size_t>(y) * w + x) * 3];
      p[0] = static_cast<std::uint8_t>(std::clamp(r + noise, 0.0, 255.0));
      p[1] = static_cast<std::uint8_t>(std::clamp(g + noise, 0.0, 255.0));
      p[2] = static_cast<std::uint8_t>(std::clamp(b + noise, 0.0, 255.0));
    }
  return px;
}

std::vector<std::int64_t> parse_shape(const std::string& text) {
  std::vector<std::int64_t> shape;
  std::stringstream ss(text);
  std::string part;
  while (std::getline(ss, part, ',')) {
    char* end = nullptr;
    long long d = std::strtoll(part.c_str(), &end, 10);
    if (part.empty() || *end || d < 1 || d > 100000) return {};
    shape.push_back(d);
  }
  return shape;
}

}  // namespace

int main(int argc, char** argv) {
  apps::apply_exec_environment("synth");
  std::string model, shape_text, out, range = "normal", head = "v4", image_size, input_size;
  int seed = 1, classes = 2;
  cli::Parser args("synth", "(--model NAME | --shape N,C,H,W) --out FILE.safetensors [--seed S] [--range normal|LO,HI]",
                   "Writes seeded random weights for a model (PyTorch state_dict names), a random input\n"
                   "tensor named 'input' (safetensors), or a synthetic road-scene PNG. Untrained: for demos,\n"
                   "tests and benchmarks.");
  args.option("model", "NAME",
              "weights for convnext_tiny, convnext_small, convnext_base, stixelnext, "
              "fasterrcnn_mobilenet_v3_large_fpn, fasterrcnn_mobilenet_v3_large_320_fpn, fasterrcnn_resnet50_fpn\n"
              "                            or detectron2_faster_rcnn_r50_fpn (under its checkpoint's names)",
              &model);
  args.option("head", "V", "stixelnext head variant v0..v4 (default v4)", &head);
  args.option("input-size", "HxW", "stixelnext: the network input size written to the metadata "
              "(stixelnext.input_height/_width; default: none, i.e. 1280x1920)", &input_size);
  args.option("classes", "N", "Faster R-CNN classes: torchvision's with the background (default 2: one device\n"
              "                            class); detectron2's foreground only, its NUM_CLASSES (default 1)",
              &classes);
  args.option("image", "WxH", "a synthetic road-scene PNG of this size instead", &image_size);
  args.option("shape", "N,C,H,W", "an input tensor 'input' of this shape instead", &shape_text);
  args.option("range", "R", "input values: 'normal' (N(0,1), default) or LO,HI uniform, e.g. 0,255", &range);
  args.option("seed", "S", "random seed (default 1)", &seed);
  args.option("out", "FILE", "output safetensors file", &out);
  args.required("out");
  args.epilog("examples:\n  synth --model convnext_tiny --out w.safetensors\n"
              "  synth --model stixelnext --head v4 --out stixelnext.safetensors\n"
              "  synth --model fasterrcnn_mobilenet_v3_large_320_fpn --classes 2 --out det.safetensors\n"
              "  synth --model detectron2_faster_rcnn_r50_fpn --classes 1 --out d2.safetensors\n"
              "  synth --image 1920x1280 --out road.png\n"
              "  synth --shape 1,3,1280,1920 --range 0,255 --out x.safetensors");
  args.parse(argc, argv);
  if (model.empty() + shape_text.empty() + image_size.empty() != 2)
    args.fail("give exactly one of --model, --shape and --image");
  nn::StixelHeadVariant variant;
  if (!nn::parse_stixel_head(head, &variant)) args.fail("--head must be one of v0..v4");
  nn::detection::FasterRcnnVariant detector;
  const bool is_detectron2 = model == nn::detection::kDetectron2FasterRcnnName;
  const bool is_detector = nn::detection::parse_faster_rcnn(model, &detector) || is_detectron2;
  if (is_detectron2 && !args.given("classes")) classes = 1;
  int in_h = 0, in_w = 0;
  if (!input_size.empty()) {
    if (model != "stixelnext") args.fail("--input-size applies to --model stixelnext only");
    if (std::sscanf(input_size.c_str(), "%dx%d", &in_h, &in_w) != 2 || in_h < 32 || in_w < 32 || in_h > 16384 ||
        in_w > 16384)
      args.fail("--input-size takes HxW with both in [32, 16384], e.g. 320x480");
  }
  if (args.given("classes") && !is_detector) args.fail("--classes applies to the detectors only");
  if (classes < 1 || classes > 10000) args.fail("--classes must be in 1..10000 (background included)");

  if (out.empty()) args.fail("--out must not be empty");
  // Interrupted, synth leaves the previous file (or none), never a temporary.
  outputs::install_interrupt_cleanup();
  try {
    nn::SplitMix64 rng(static_cast<std::uint64_t>(seed));
    weights::Writer w;
    if (!image_size.empty()) {
      int iw = 0, ih = 0;
      if (std::sscanf(image_size.c_str(), "%dx%d", &iw, &ih) != 2 || iw < 8 || ih < 8 || iw > 16384 || ih > 16384)
        args.fail("--image takes WxH, e.g. 1920x1280");
      auto px = road_scene(iw, ih, rng);
      const std::vector<std::uint8_t> png = imageio::encode_png(px.data(), iw, ih, 3);
      outputs::write_file(out, png.data(), png.size());
      return 0;
    }
    if (!model.empty()) {
      auto specs = model_specs(model, variant, classes);
      if (specs.empty()) args.fail("unknown model '" + model + "'");
      w = nn::synthetic_weights(specs, static_cast<std::uint64_t>(seed));
      w.set_metadata("model", model);
      if (model == "stixelnext") {
        w.set_metadata("stixelnext.head", head);
        w.set_metadata("stixelnext.anchors", "tangent:4,66,64");
        w.set_metadata("stixelnext.normalization", "raw255");
        if (in_h > 0) {
          w.set_metadata("stixelnext.input_height", std::to_string(in_h));
          w.set_metadata("stixelnext.input_width", std::to_string(in_w));
        }
      }
      if (is_detector) w.set_metadata("classes", std::to_string(classes));
    } else {
      w.set_metadata("format", "roadnn-v1");
      w.set_metadata("generator", "synth seed " + std::to_string(seed) + " (random input)");
      auto shape = parse_shape(shape_text);
      if (shape.empty()) args.fail("--shape takes positive comma-separated sizes, e.g. 1,3,224,224");
      double lo = 0, hi = 0;
      const bool normal = range == "normal";
      if (!normal && std::sscanf(range.c_str(), "%lf,%lf", &lo, &hi) != 2)
        args.fail("--range takes 'normal' or LO,HI");
      if (!normal && !(std::isfinite(lo) && std::isfinite(hi) && lo <= hi && std::isfinite(hi - lo)))
        args.fail("--range LO,HI needs finite numbers with LO <= HI, got '" + range + "'");
      std::size_t n = 1;
      for (auto d : shape) n *= static_cast<std::size_t>(d);
      if (n > (std::size_t{1} << 31)) args.fail("--shape is too large");
      std::vector<float> v(n);
      for (auto& x : v) x = static_cast<float>(normal ? rng.normal() : lo + (hi - lo) * rng.uniform());
      w.add_f32("input", shape, v.data());
    }
    w.write(out, &outputs::temporary_file_hooks());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "synth: %s\n", e.what());
    return 1;
  }
  return 0;
}
