// stixelnext: images -> Stixel Worlds (pyStixel-lib .stx1, CSV or JSON), with
// optional overlay and bird's-eye-view pictures and DBSCAN clustering.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <cerrno>
#include <sys/stat.h>
#include <vector>

#include "apps/common/cli.h"
#include "weights/file_io.h"
#include "apps/common/exec_env.h"
#include "apps/common/precision_option.h"
#include "apps/common/image_io.h"
#include "apps/common/output_files.h"
#include "apps/common/unused_tensors.h"
#include "apps/stixelnext/calibration.h"
#include "nn/isa.h"
#include "nn/resize.h"
#include "nn/threads.h"
#include "stixel/frame_pipeline.h"
#include "stixel/image_header.h"
#include "stixel/model_file.h"
#include "stixel/point_cloud.h"
#include "stixel/predictor.h"
#include "stixel/projection.h"
#include "stixel/render.h"
#include "stixel/stx1.h"
#include "stixel/text_formats.h"

namespace {

using Clock = std::chrono::steady_clock;

enum Stage { kDecode, kPreprocess, kNetwork, kExtraction, k3d, kClustering, kEncode, kStages };
const char* kStageNames[kStages] = {"decode", "preprocess", "network", "extraction", "3D", "clustering", "encode"};

struct StageTimer {
  double ms[kStages] = {};
  template <class F>
  auto time(Stage s, F&& f) {
    auto t0 = Clock::now();
    struct Add {
      double* slot;
      Clock::time_point t0;
      ~Add() { *slot += std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }
    } add{&ms[s], t0};
    return f();
  }
};

std::string stem_of(const std::string& path) {
  std::string name = path.substr(path.find_last_of('/') + 1);
  auto dot = name.find_last_of('.');
  return dot == std::string::npos || dot == 0 ? name : name.substr(0, dot);
}

// A UTF-8-safe name for the context and the output file.
std::string clean_name(const std::string& stem) {
  std::string out = stixel::is_valid_utf8(stem) ? stem : std::string();
  if (out.empty())
    for (unsigned char ch : stem) out += (ch >= 0x20 && ch < 0x7f) ? static_cast<char>(ch) : '_';
  return out;
}

stixel::RgbImage background_at(const imageio::Image& img, int w, int h) {
  stixel::RgbImage bg;
  bg.width = w;
  bg.height = h;
  bg.pixels.resize(static_cast<std::size_t>(w) * h * 3);
  if (img.width == w && img.height == h) {
    bg.pixels = img.u8;
    return bg;
  }
  std::vector<float> src(img.u8.begin(), img.u8.end()), dst(bg.pixels.size());
  nn::resize_bilinear(nn::ConstTensorView(src.data(), {1, img.height, img.width, 3}), nn::TensorView{dst.data(), {1, h, w, 3}});
  for (std::size_t i = 0; i < dst.size(); ++i)
    bg.pixels[i] = static_cast<std::uint8_t>(std::clamp(std::lround(dst[i]), 0L, 255L));
  return bg;
}

// True for a file the .stx1 can carry as it is: PNG or JPEG (by magic, what
// pyStixel-lib and our reader recognise) decoding to 8-bit RGB, so that
// pyStixel-lib's point-cloud colours (PIL getpixel -> r, g, b) work on it.
bool embeds_as_is(const std::vector<std::uint8_t>& file, const std::string& path) {
  const stixel::ImageFormat f = stixel::image_format(file.data(), file.size());
  if (f != stixel::ImageFormat::Png && f != stixel::ImageFormat::Jpeg) return false;
  const imageio::ImageInfo info = imageio::probe(file.data(), file.size(), path);
  return info.channels == 3 && info.bit_depth == 8;
}

bool parse_size(const std::string& text, int* h, int* w) {
  return std::sscanf(text.c_str(), "%dx%d", h, w) == 2 && *h >= 32 && *w >= 32 && *h <= 16384 && *w <= 16384;
}

}  // namespace

int main(int argc, char** argv) {
  apps::apply_exec_environment("stixelnext");
  std::string weights_path, calib_path, out_dir = "stixels", format = "stx1", head, anchors, norm, input_size,
                                        cluster_axes = "0,2", precision, max_pixels, preset, points;
  double threshold = 0.36, train_focal = 0;
  int threads = 0, columns = 0, stixel_width = 0;
  bool overlay = false, bev = false, bev_fit = false, cluster = false, profile = false, embed_image = false,
       no_embed_image = false, quiet = false, calib_per_image = false;
  std::vector<std::string> images;

  cli::Parser args("stixelnext", "--weights W.safetensors [options] IMAGE...",
                   "StixelNExT++ on images: writes one Stixel World per image (pyStixel-lib .stx1 by default)\n"
                   "to OUT_DIR/<image stem>.<format>, optionally with overlay and bird's-eye-view pictures.");
  args.option("weights", "FILE", "StixelNExT++ weights (safetensors; features.* and classifier.* state_dict names)", &weights_path);
  args.option("calib", "FILE", "calibration JSON for every image: {\"K\": [9], \"T\": [16, optional], \"width\": W, "
              "\"height\": H} or the authors' {\"fx\", \"fy\", \"cx\", \"cy\"}", &calib_path);
  args.flag("calib-per-image", "each image's own calibration: <image folder>/<stem>.json (either form), as "
            "StixelNExT_Pro's inference_from_file reads them", &calib_per_image);
  args.option("threshold", "P", "keep candidates with probability >= P, in [0, 1] (default 0.36; 0 keeps all)", &threshold);
  args.option("out-dir", "DIR", "output folder (default ./stixels, created if needed)", &out_dir);
  args.option("format", "F", "stx1 (default), csv or json", &format);
  args.flag("overlay", "also write <stem>_overlay.png: stixels on the image, far to near, RdYlGn by depth", &overlay);
  args.flag("bev", "also write <stem>_bev.png: bird's-eye view, fixed window 70 x 70 m (needs a calibration)", &bev);
  args.flag("bev-fit", "the bird's-eye view as pyStixel-lib's draw_stixels_birds_eye_view: window fitted to the data, "
            "2-px lines at alpha 0.9 (implies --bev)", &bev_fit);
  args.option("points", "FMT", "also write the 3D point cloud of pyStixel-lib's convert_to_point_cloud: "
              "<stem>_points.ply (binary: x y z float, colour, stixel index, cluster) or <stem>_points.csv "
              "(needs a calibration)", &points);
  args.flag("cluster", "DBSCAN on the stixels' top points (eps 1.42 m, min_samples 2; needs a calibration)", &cluster);
  args.option("cluster-axes", "A,B", "the two 3D axes of the bird's-eye plane (default 0,2 = x,z for an optical-frame "
              "calibration; 0,1 for Waymo vehicle-frame K/T)", &cluster_axes);
  args.option("threads", "N", "threads (default: all cores)", &threads);
  args.flag("profile", "print the network's per-layer time table", &profile);
  args.option("precision", "P", apps::kPrecisionHelp, &precision);
  args.option("preset", "NAME", "settings of a published setup: waymo (1280x1920, 240 x 8 px, raw255) or coopscenes "
              "(1200x1920, 120 x 16 px, imagenet); over the weights' metadata, under the flags below", &preset);
  args.option("head", "V", "force the head variant v0..v4 (default: the metadata's, else detected; v1 and v3 share "
              "their tensors)", &head);
  args.option("anchors", "SPEC", "depth anchors: tangent:4,66,64 (default) or linear:START,END,N", &anchors);
  args.option("normalization", "MODE", "raw255 (default, as trained), unit (/255) or imagenet", &norm);
  args.option("input-size", "HxW", "network input size (default 1280x1920 or the weights' metadata)", &input_size);
  args.option("columns", "U", "output columns (default: input width / stixel width)", &columns);
  args.option("stixel-width", "PX", "pixels per column (default 8)", &stixel_width);
  args.option("train-focal", "F", "focal length (px) of the training camera: depths are scaled by f_camera / F", &train_focal);
  args.flag("no-embed-image", "leave the image out of the .stx1 (default: embedded, as the authors' tools do: the "
            "input file's own PNG/JPEG bytes, or a PNG of the network-size image when it was resized)", &no_embed_image);
  args.flag("embed-image", "(the default now; kept for old command lines)", &embed_image);
  args.option("max-pixels", "N", "refuse images above N megapixels (1 Mpx = 2^20 pixels) from their header, before decoding (default 64)", &max_pixels);
  args.flag("quiet", "no progress line", &quiet);
  args.positionals("IMAGE...", "PNG or JPEG images", &images);
  args.required("weights");
  args.epilog("Settings default to the weights' __metadata__ (stixelnext.input_height/_width, columns, stixel_width,\n"
              "anchors, normalization, head; weights/export.py --preset/--meta writes them), then --preset, then the\n"
              "flags. Tensors that fit both V1 and V3 with nothing saying which run as V1 with a warning. Images of\n"
              "another size are resized bilinearly and K is scaled to match.\n\nexamples:\n"
              "  stixelnext --weights stixelnext.safetensors --calib cam.json --overlay --bev --cluster --out-dir out frame_*.png\n"
              "  stixelnext --weights w.safetensors --preset waymo --calib-per-image --points ply --out-dir out images/*.png");
  args.parse(argc, argv);
  imageio::DecodeLimits limits;
  if (args.given("max-pixels") && !imageio::parse_max_pixels(max_pixels, &limits.max_pixels))
    args.fail("--max-pixels takes megapixels > 0, e.g. 64 or 0.5");
  if (images.empty()) args.fail("no IMAGE given");
  if (!(threshold >= 0 && threshold <= 1)) args.fail("--threshold must be in [0, 1]");
  if (format != "stx1" && format != "csv" && format != "json") args.fail("--format must be stx1, csv or json");
  if (bev_fit) bev = true;
  if (!calib_path.empty() && calib_per_image) args.fail("--calib and --calib-per-image exclude each other");
  const bool has_calib = !calib_path.empty() || calib_per_image;
  if (!points.empty() && points != "ply" && points != "csv") args.fail("--points must be ply or csv");
  if ((bev || cluster || !points.empty()) && !has_calib)
    args.fail("--bev, --cluster and --points need --calib or --calib-per-image (3D needs the intrinsics)");
  if (train_focal < 0 || (args.given("train-focal") && train_focal <= 0)) args.fail("--train-focal must be positive");
  if (args.given("train-focal") && !has_calib) args.fail("--train-focal needs --calib or --calib-per-image");
  std::map<std::string, std::string> preset_md;
  if (!preset.empty() && !stixel::preset_metadata(preset, &preset_md)) args.fail("--preset must be waymo or coopscenes");
  embed_image = !no_embed_image && format == "stx1";  // CSV and JSON exports carry no image
  int axis_a = 0, axis_b = 2;
  if (std::sscanf(cluster_axes.c_str(), "%d,%d", &axis_a, &axis_b) != 2 || axis_a < 0 || axis_a > 2 || axis_b < 0 ||
      axis_b > 2 || axis_a == axis_b)
    args.fail("--cluster-axes takes two different axes out of 0,1,2, e.g. 0,2");
  nn::set_num_threads(threads);
  const nn::Precision prec = apps::precision_option(args, precision);

  // Every output of the run, known before anything is read or written: none may
  // replace an input or another output (two same.png from different folders).
  auto output_base = [&](const std::string& image) { return out_dir + "/" + clean_name(stem_of(image)); };
  try {
    outputs::Plan plan;
    plan.input(weights_path, "weights");
    if (!calib_path.empty()) plan.input(calib_path, "calibration");
    for (const std::string& image : images) plan.input(image);
    if (calib_per_image)
      for (const std::string& image : images) plan.input(stixelnext::per_image_calibration_path(image), "calibration");
    for (const std::string& image : images) {
      const std::string base = output_base(image);
      plan.output(base + "." + format, image);
      if (overlay) plan.output(base + "_overlay.png", image);
      if (bev) plan.output(base + "_bev.png", image);
      if (!points.empty()) plan.output(base + "_points." + points, image);
    }
    plan.check();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "stixelnext: %s\n", e.what());
    return 1;
  }
  outputs::install_interrupt_cleanup();

  std::unique_ptr<stixel::Predictor> predictor;
  stixelnext::Calibration calib;
  try {
    weights::SafeTensors w = weights::SafeTensors::load(weights_path);
    // The file's metadata (a declared head checked against the tensors), then the preset.
    stixel::ModelSettings s = stixel::settings_from_weights(w);
    if (!preset.empty()) stixel::apply_metadata(preset_md, "--preset " + preset, &s);
    if (!head.empty()) {
      nn::StixelHeadVariant v;
      if (!nn::parse_stixel_head(head, &v)) args.fail("--head must be one of v0, v1, v2, v3, v4");
      s.head = v;
    }
    if (!anchors.empty()) s.anchors = stixel::parse_anchor_spec(anchors, "--anchors");
    if (!norm.empty() && !stixel::parse_normalization(norm, &s.normalization))
      args.fail("--normalization must be raw255, unit or imagenet");
    if (!input_size.empty() && !parse_size(input_size, &s.input_height, &s.input_width))
      args.fail("--input-size takes HxW with both at least 32, e.g. 1280x1920");
    if (args.given("stixel-width")) {
      if (stixel_width < 1 || stixel_width > 1024) args.fail("--stixel-width must be in [1, 1024]");
      s.stixel_width = stixel_width;
    }
    if (args.given("columns")) {
      if (columns < 1 || columns > 16384) args.fail("--columns must be in [1, 16384]");
      s.columns = columns;
    }
    s.precision = prec;
    predictor = std::make_unique<stixel::Predictor>(w, s);
    // Once per run, not per image.
    const std::string ambiguous = stixel::head_ambiguity_warning(w, s.head);
    if (!ambiguous.empty()) std::fprintf(stderr, "stixelnext: warning: %s\n", ambiguous.c_str());
    apps::warn_unused_tensors("stixelnext", w, predictor->model().used_tensors(), "StixelNExT++");
    if (!calib_path.empty()) {
      calib = stixelnext::read_calibration(calib_path);
      stixel::Projection check(calib.K, calib.T, calib_path);  // a singular K4 * T fails here, once
    }
    {
      std::error_code ec;  // every missing level, as mkdir -p
      std::filesystem::create_directories(out_dir, ec);
      if (ec || !std::filesystem::is_directory(out_dir))
        throw std::runtime_error(out_dir + ": cannot create the output folder (" +
                                 (ec ? ec.message() : std::string("not a folder")) + ")");
    }
    const auto& st = predictor->settings();
    if (!quiet)
      std::fprintf(stderr, "stixelnext: head %s, input %dx%d, %d columns of %d px, anchors %s, %s input, kernels %s (%s), %d threads\n",
                   nn::stixel_head_name(predictor->model().head().variant()), st.input_height, st.input_width,
                   st.effective_columns(), st.stixel_width, stixel::anchor_spec(st.anchors).c_str(),
                   stixel::normalization_name(st.normalization), nn::isa_name(nn::active_isa()),
                   nn::precision_name(st.precision), nn::num_threads());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "stixelnext: %s\n", e.what());
    return 1;
  }

  const auto& settings = predictor->settings();
  const int H = settings.input_height, W = settings.input_width;
  StageTimer timer;
  int failed = 0, done = 0;
  bool told_resize = false;
  predictor->model().profiler().set_enabled(profile);
  stixel::FrameOptions fo;  // the per-image pipeline: preprocess, network, extraction, 3D, clustering
  fo.threshold = threshold;
  fo.train_focal = train_focal;
  fo.cluster = cluster;
  fo.cluster_options.axis_a = axis_a;
  fo.cluster_options.axis_b = axis_b;
  for (std::size_t i = 0; i < images.size(); ++i) {
    const std::string& path = images[i];
    try {
      // The calibration this image uses: the one file, or its own <stem>.json.
      stixelnext::Calibration cal = calib;
      std::string cal_source = calib_path;
      if (calib_per_image) {
        cal_source = stixelnext::per_image_calibration_path(path);
        cal = stixelnext::read_calibration(cal_source);
        stixel::Projection check(cal.K, cal.T, cal_source);
      }
      if (has_calib) fo.camera = stixel::FrameCamera{cal.K, cal.T, cal_source};
      // The file's own bytes are kept: they are what the .stx1 embeds.
      std::vector<std::uint8_t> file;
      imageio::Image img = timer.time(kDecode, [&] {
        file = imageio::read_image_file(path);
        return imageio::decode(file.data(), file.size(), path, 3, false, limits);
      });
      if (has_calib && cal.has_size() && (img.width != cal.width || img.height != cal.height))
        throw std::runtime_error(path + ": image is " + std::to_string(img.width) + "x" + std::to_string(img.height) +
                                 " but the calibration " + cal_source + " is for " + std::to_string(cal.width) + "x" +
                                 std::to_string(cal.height));
      // The note comes before the frame runs, as it always has (even if the frame then fails).
      if ((img.width != W || img.height != H) && !told_resize) {
        std::fprintf(stderr, "stixelnext: note: %dx%d images are resized to %dx%d (bilinear)%s\n", img.width, img.height,
                     W, H, has_calib ? " and K is scaled to match" : "");
        told_resize = true;
      }
      stixel::FrameResult frame =
          stixel::process_frame(*predictor, {img.u8.data(), img.width, img.height, 3 * static_cast<std::size_t>(img.width)}, fo);
      timer.ms[kPreprocess] += frame.times.preprocess;
      timer.ms[kNetwork] += frame.times.network;
      timer.ms[kExtraction] += frame.times.extraction;
      timer.ms[k3d] += frame.times.points;
      timer.ms[kClustering] += frame.times.clustering;
      stixel::StixelWorld& world = frame.world;
      const std::string name = clean_name(stem_of(path));
      world.context.name = name;
      if (frame.projection) {
        auto& c = world.context.calibration;
        c.img_name = path.substr(path.find_last_of('/') + 1);
        if (!stixel::is_valid_utf8(c.img_name)) c.img_name = name;
      }
      // pyStixel-lib reads the embedded image in the stixels' pixel frame (the
      // network input): the file itself when it is that size and an 8-bit RGB
      // PNG or JPEG, else a PNG of the network-size pixels.
      const bool embed_file = embed_image && !frame.resized && embeds_as_is(file, path);
      stixel::RgbImage bg;
      if (overlay || !points.empty() || (embed_image && !embed_file)) bg = background_at(img, W, H);
      timer.time(kEncode, [&] {
        // One image's outputs appear together or not at all: all are written as
        // temporaries first, then renamed.
        if (embed_file)
          world.image = std::move(file);
        else if (embed_image)
          world.image = imageio::encode_png(bg.pixels.data(), W, H, 3);
        const std::string base = output_base(path);
        outputs::FileSet set;
        if (format == "stx1") {
          set.add(base + ".stx1", stixel::encode_stx1(world));
        } else {
          set.add(base + "." + format, format == "csv" ? stixel::to_csv(world, {path, false}) : stixel::to_json(world));
        }
        if (overlay) {
          stixel::OverlayOptions oo;
          oo.min_confidence = threshold;
          oo.color_by_cluster = cluster;
          auto pic = stixel::render_overlay(world, bg, oo);
          set.add(base + "_overlay.png", imageio::encode_png(pic.pixels.data(), pic.width, pic.height, 3));
        }
        if (bev) {
          stixel::BevOptions bo;
          bo.min_confidence = threshold;
          bo.lateral_axis = axis_a;
          bo.forward_axis = axis_b;
          if (cluster) bo.color = stixel::BevOptions::Color::Cluster;
          auto pic = bev_fit ? stixel::render_bev_fitted(world, *frame.projection, bo)
                             : stixel::render_bev(world, *frame.projection, bo);
          set.add(base + "_bev.png", imageio::encode_png(pic.pixels.data(), pic.width, pic.height, 3));
        }
        if (!points.empty()) {
          stixel::PointCloudOptions po;
          po.image = &bg;
          po.cluster_labels = cluster;
          const stixel::PointCloud cloud = stixel::world_point_cloud(world, *frame.projection, po);
          if (points == "ply")
            set.add(base + "_points.ply", stixel::to_ply(cloud, "roadnn stixelnext: " + name));
          else
            set.add(base + "_points.csv", stixel::to_points_csv(cloud));
        }
        set.commit();
        return 0;
      });
      ++done;
      if (!quiet)
        std::fprintf(stderr, "[%zu/%zu] %s: %zu stixels%s\n", i + 1, images.size(), path.c_str(), world.stixels.size(),
                     cluster ? (", " + std::to_string(world.context.clusters + 1) + " clusters").c_str() : "");
    } catch (const std::exception& e) {
      ++failed;
      std::fprintf(stderr, "stixelnext: %s\n", e.what());
    }
  }
  if (profile && done) std::fputs(predictor->model().profiler().table().c_str(), stdout);
  if (done) {
    std::printf("stage times, mean over %d image%s (ms):", done, done == 1 ? "" : "s");
    double total = 0;
    for (int s = 0; s < kStages; ++s) {
      std::printf(" %s %.2f", kStageNames[s], timer.ms[s] / done);
      total += timer.ms[s] / done;
    }
    std::printf("  | total %.2f\n", total);
  }
  if (failed && images.size() > 1) std::fprintf(stderr, "stixelnext: %d of %zu images failed\n", failed, images.size());
  return failed ? 1 : 0;
}
