// shle: stereo height-limit estimation over one sequence folder.
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "apps/common/cli.h"
#include "apps/common/exec_env.h"
#include "apps/common/image_io.h"
#include "apps/common/output_files.h"
#include "apps/shle/detector_option.h"
#include "apps/shle/frame_loader.h"
#include "apps/shle/height_plot.h"
#include "apps/shle/report.h"
#include "nn/threads.h"
#include "shle/box_source.h"
#include "shle/detector_box_source.h"
#include "shle/detectron2_box_source.h"
#include "shle/error.h"
#include "shle/pipeline.h"
#include "shle/released_box_source.h"

namespace {

void progress_bar(std::size_t done, std::size_t total) {
  const int width = 40;
  int filled = total ? static_cast<int>(width * done / total) : width;
  std::string bar(filled, '#');
  bar.resize(width, '.');
  std::fprintf(stderr, "\rshle [%s] %zu/%zu frames", bar.c_str(), done, total);
  if (done == total) std::fputc('\n', stderr);
  std::fflush(stderr);
}

}  // namespace

int main(int argc, char** argv) {
  apps::apply_exec_environment("shle");
  std::string sequence, calib, calib_format = "plain", boxes = "annotations", rule = "paper", box_test = "whole";
  std::string tracker = "ncc", out_dir = "shle_out", max_pixels;
  std::string coco_images;
  std::vector<std::string> box_paths;
  shleapp::DetectorChoice det;
  double gt_height = 0, bf = 0;
  bool filter_single = false, no_kde = false, no_depth = false, no_kalman = false, compat = false, quiet = false;
  bool gate = false;
  shle::PipelineOptions opt;
  shle::HeightOptions& h = opt.height;

  cli::Parser p("shle", "--sequence DIR --calib C.json [--boxes KIND [PATH]] [options]",
                "Stereo height-limit estimation (SHLE): the clearance of a bar, bridge or cable ahead,\n"
                "from the left images, disparity maps and boxes of one sequence. Writes OUT/frames.csv,\n"
                "OUT/summary.json and OUT/heights.png.");
  p.option("sequence", "DIR", "sequence folder (left_colorimages/ + disparity_images/, or left/ + disparity/)",
           &sequence);
  p.option("calib", "PATH", "calibration JSON (or the adas_params folder with --calib-format smartereye)", &calib);
  p.option("calib-format", "FMT", "plain (default) or smartereye (calibData.json + DepthCalib.json)",
           &calib_format);
  p.option("bf", "M_PX", "override baseline x focal length (metre-pixels)", &bf);
  p.option("boxes", "SRC",
           "annotations (LabelMe beside the images, default), a CSV frame,x0,y0,x1,y1,score, detector "
           "(Faster R-CNN on every left image, with --detector-weights), released-stage1 DIR (the released "
           "stage 1's per-frame [[x, y], [w, h]] JSON folder) or coco-results FILE (detectron2's "
           "coco_instances_results.json)",
           &boxes);
  p.positionals("PATH", "the folder after --boxes released-stage1, the file after --boxes coco-results", &box_paths);
  p.option("coco-images", "FILE|sorted",
           "required with --boxes coco-results: the COCO dataset file the detector ran on "
           "(test2017_images_0XX.json), which maps image_id to an image; or 'sorted': image_id k is the k-th "
           "image in file-name order",
           &coco_images);
  p.flag("gate-with-annotations",
         "the released frame gate: use a frame only if its box hits its LabelMe annotation box "
         "(IoU > 0, or right edge within 200 px of the annotation's left edge and top within 20 px). "
         "Uses the ground truth: for reproducing the released figures only",
         &gate);
  shleapp::add_detector_options(p, &det);
  p.option("box-rule", "RULE",
           "paper (default: drop left, low, top-edge boxes, best score) or widest (released; the default with "
           "coco-results)",
           &rule);
  p.option("min-score", "S", "keep candidates with score > S (default 0.3)", &opt.box_rule.min_score);
  p.option("box-test", "T", "paper rule position test: whole (box entirely in the region, default) or centre",
           &box_test);
  p.flag("filter-single-box", "apply the paper rule's position filters to a lone candidate too", &filter_single);
  p.option("tracker", "KIND",
           "fills frames between boxes: ncc (default), mil (OpenCV MIL port) or none (default with "
           "released-stage1, whose files hold the tracked boxes already)",
           &tracker);
  p.option("search-radius", "PX", "tracker search radius (default 25)", &opt.ncc.search_radius);
  p.option("gt-height", "M", "true height: adds HE / HER to the summary and the plot", &gt_height);
  p.option("out-dir", "OUT", "output folder (default shle_out)", &out_dir);
  p.option("extend-top", "PX", "box extension upwards (default 20)", &h.extend_top);
  p.option("extend-bottom", "PX", "box extension downwards (default 20)", &h.extend_bottom);
  p.option("min-height", "M", "keep points higher than this above the road (default 1.5)", &h.min_height);
  p.option("bandwidth", "M", "KDE Gaussian bandwidth, metres (default 2.5)", &h.bandwidth);
  p.option("grid-step", "M", "KDE grid step, metres (default 1 as released; finer is an improvement)",
           &h.grid_step);
  p.option("sigma", "M", "depth window half width around the KDE mode (default 0.6)", &h.sigma);
  p.option("lowest-n", "N", "average the N lowest points (default 10)", &h.lowest_n);
  p.flag("no-kde", "centre depth = mean depth instead of the KDE mode", &no_kde);
  p.flag("no-depth-filter", "keep all points instead of the depth window", &no_depth);
  p.flag("no-kalman", "no temporal filter: scene height = mean raw height", &no_kalman);
  p.flag("kalman-compat", "the released code's Kalman off-by-one (outputs shifted, last value 0)", &compat);
  p.option("q", "VAR", "Kalman process noise (default 1e-3)", &opt.temporal.kalman.q);
  p.option("r", "VAR", "Kalman measurement noise (default 1e-2)", &opt.temporal.kalman.r);
  p.option("p0", "VAR", "Kalman initial variance (default 6)", &opt.temporal.kalman.p0);
  p.option("max-pixels", "N", "refuse images above N megapixels (1 Mpx = 2^20 pixels) from their header, before decoding (default 64)",
           &max_pixels);
  p.flag("quiet", "no progress bar and no per-frame warnings", &quiet);
  p.required("sequence");
  p.required("calib");
  p.epilog(
      "example:\n"
      "  shle_synth --out /tmp/scene --device bar --height 3.3\n"
      "  shle --sequence /tmp/scene --calib /tmp/scene/calib.json --gt-height 3.3 --out-dir /tmp/out\n"
      "  synth --model fasterrcnn_mobilenet_v3_large_320_fpn --out det.safetensors   # untrained\n"
      "  shle --sequence /tmp/scene --calib /tmp/scene/calib.json --boxes detector \\\n"
      "       --detector-weights det.safetensors --detector-model fasterrcnn_mobilenet_v3_large_320_fpn\n"
      "  # the released code's files (scene 17 of Disparity Height):\n"
      "  shle --sequence data/demo_data/val/images_017 --calib data/demo_data/adas_params --calib-format smartereye \\\n"
      "       --boxes released-stage1 Stage1/faster_rcnn_output/tracking_mil_json/images_017 \\\n"
      "       --gate-with-annotations --kalman-compat --gt-height 2.85");
  p.parse(argc, argv);
  imageio::DecodeLimits limits;
  if (p.given("max-pixels") && !imageio::parse_max_pixels(max_pixels, &limits.max_pixels))
    p.fail("--max-pixels takes megapixels > 0, e.g. 64 or 0.5");

  const bool released_stage1 = boxes == "released-stage1", coco_results = boxes == "coco-results";
  if (released_stage1 || coco_results) {
    if (box_paths.size() != 1)
      p.fail(std::string("--boxes ") + boxes + " takes one " + (released_stage1 ? "folder" : "file") +
             " after it, e.g. --boxes " + boxes + (released_stage1 ? " tracking_mil_json/images_017" : " coco_instances_results.json"));
    if (released_stage1 && !p.given("tracker")) tracker = "none";
    if (coco_results && !p.given("box-rule")) rule = "widest";
  } else if (!box_paths.empty()) {
    p.fail("unexpected argument '" + box_paths.front() + "' (only --boxes released-stage1 DIR and --boxes "
           "coco-results FILE take a path after them)");
  }
  if (p.given("coco-images") && !coco_results) p.fail("--coco-images needs --boxes coco-results FILE");
  if (coco_results && coco_images.empty())
    p.fail("--boxes coco-results needs --coco-images FILE (the COCO dataset file the detector ran on, e.g. "
           "test2017_images_017.json) or --coco-images sorted (image_id k = k-th image in file-name order)");
  opt.gate_with_annotations = gate;
  opt.temporal.use_kalman = !no_kalman;
  opt.temporal.kalman_compat = compat;
  h.use_kde = !no_kde;
  h.use_depth_window = !no_depth;
  opt.tracker = tracker;
  opt.mil.search_radius = opt.ncc.search_radius;
  opt.box_rule.paper.filter_single = filter_single;
  if (box_test == "centre" || box_test == "center")
    opt.box_rule.paper.centre_test = true;
  else if (box_test != "whole")
    p.fail("--box-test must be whole or centre");
  if (p.given("gt-height")) {
    if (!(gt_height > 0) || !std::isfinite(gt_height)) p.fail("--gt-height must be > 0");
    opt.has_gt_height = true;
    opt.gt_height = gt_height;
  }
  if (!(opt.temporal.kalman.q >= 0 && opt.temporal.kalman.r > 0 && opt.temporal.kalman.p0 >= 0) ||
      !std::isfinite(opt.temporal.kalman.q + opt.temporal.kalman.r + opt.temporal.kalman.p0))
    p.fail("Kalman variances must be finite, q >= 0, r > 0, p0 >= 0");

  const bool detector = boxes == "detector";
  shleapp::check_detector_options(p, detector, &det);

  try {
    opt.box_rule.rule = shle::parse_box_rule(rule);
    shle::validate(h);
    shle::make_tracker(tracker, opt.ncc);
    if (opt.ncc.search_radius < 1) throw shle::Error("--search-radius must be >= 1");
  } catch (const std::exception& e) {
    p.fail(e.what());
  }

  try {
    shle::Sequence seq = shle::scan_sequence(sequence);
    const std::filesystem::path out(out_dir);
    const std::string csv_path = (out / "frames.csv").string(), summary_path = (out / "summary.json").string(),
                      plot_path = (out / "heights.png").string();
    {
      // Before anything is read or written: no output may replace an input.
      outputs::Plan plan;
      std::error_code ec;
      if (std::filesystem::is_directory(calib, ec)) {
        for (const auto& e : std::filesystem::directory_iterator(calib, ec)) plan.input(e.path().string(), "calibration");
      } else {
        plan.input(calib, "calibration");
      }
      if (!detector && boxes != "annotations" && !released_stage1 && !coco_results) plan.input(boxes, "boxes file");
      if (coco_results) plan.input(box_paths.front(), "COCO results");
      if (p.given("coco-images") && coco_images != "sorted") plan.input(coco_images, "COCO dataset file");
      if (released_stage1 && std::filesystem::is_directory(box_paths.front(), ec))
        for (const auto& e : std::filesystem::directory_iterator(box_paths.front(), ec))
          plan.input(e.path().string(), "released stage-1 box file");
      if (detector) plan.input(det.weights, "detector weights");
      for (const shle::FrameFiles& f : seq.frames) {
        plan.input(f.image);
        plan.input(f.annotation);
        if (!f.disparity.empty()) plan.input(f.disparity);
      }
      plan.output(csv_path);
      plan.output(summary_path);
      plan.output(plot_path);
      plan.check();
    }
    outputs::install_interrupt_cleanup();

    shle::Calibration cal;
    if (calib_format == "plain")
      cal = shle::load_calibration(calib);
    else if (calib_format == "smartereye")
      cal = shle::load_smartereye_calibration(calib);
    else
      p.fail("--calib-format must be plain or smartereye");
    if (p.given("bf")) {
      if (!(bf > 0) || !std::isfinite(bf)) p.fail("--bf must be > 0");
      cal.bf = bf;
    }
    std::unique_ptr<shle::BoxSource> source;
    shleapp::DetectorDescription det_desc;
    shleapp::PngFrameLoader loader(limits);
    if (released_stage1 || coco_results) {
      std::vector<shle::ImageSize> sizes = shle::sequence_image_sizes(seq, loader, cal);
      if (released_stage1)
        source = std::make_unique<shle::ReleasedStage1Source>(box_paths.front(), seq, sizes);
      else
        source = std::make_unique<shle::CocoResultsSource>(box_paths.front(), coco_images, seq, sizes);
    } else if (boxes == "annotations") {
      source = std::make_unique<shle::AnnotationBoxSource>();
    } else if (detector) {
      source = shleapp::make_detector_source(det, "shle", false, &det_desc);
    } else {
      source = std::make_unique<shle::BoxesFileSource>(boxes, seq.frames.size());
    }

    std::filesystem::create_directories(out_dir);
    bool bar = !quiet && isatty(2);
    shle::SequenceRun run = shle::run_sequence(seq, cal, *source, loader, opt,
                                               bar ? shle::Progress(progress_bar) : shle::Progress());

    if (!quiet) {
      int shown = 0, total = 0;
      for (const shle::FrameRecord& r : run.frames)
        for (const std::string& msg : r.problems) {
          if (shown < 30) {
            std::fprintf(stderr, "shle: warning: frame %d: %s\n", r.index, msg.c_str());
            ++shown;
          }
          ++total;
        }
      if (total > shown)
        std::fprintf(stderr, "shle: warning: ... %d more problems, see %s/summary.json\n", total - shown,
                     out_dir.c_str());
    }

    std::string csv = shleapp::frames_csv(run);
    shleapp::RunDescription desc{sequence, shle::layout_name(seq.layout), calib, source->name(), rule, tracker, opt,
                                 det_desc, "", ""};
    if (released_stage1 || coco_results) desc.box_path = box_paths.front();
    if (coco_results) desc.coco_images = coco_images;
    std::string summary = shleapp::summary_json(run, desc);
    shleapp::HeightPlotData plot;
    plot.frames = static_cast<int>(run.frames.size());
    for (const shle::FrameRecord& r : run.frames) {
      if (r.stage2.has_height) plot.raw.emplace_back(r.index, r.stage2.height);
      if (r.has_filtered) plot.filtered.emplace_back(r.index, r.filtered);
    }
    plot.has_gt = opt.has_gt_height;
    plot.gt = opt.gt_height;
    plot.has_scene = run.heights.has_scene_height;
    plot.scene = run.heights.scene_height;
    shleapp::Canvas canvas = shleapp::draw_height_plot(plot);
    // The three files are one set: all written as temporaries, then renamed, so an
    // interrupted run never leaves this run's frames.csv beside the last run's summary.
    outputs::FileSet set;
    set.add(csv_path, csv);
    set.add(summary_path, summary);
    set.add(plot_path, imageio::encode_png(canvas.rgb().data(), canvas.width(), canvas.height(), 3));
    set.commit();

    if (run.heights.has_scene_height) {
      std::printf("scene height %.3f m over %zu of %zu frames", run.heights.scene_height, run.frames_used,
                  run.frames.size());
      if (run.has_errors)
        std::printf(" (truth %.3f m, HE %+.3f m, HER %+.2f %%)", opt.gt_height, run.scene_error.he,
                    100.0 * run.scene_error.her);
      std::printf("\n");
    } else {
      std::printf("no height: none of the %zu frames has one (see %s/summary.json)\n", run.frames.size(),
                  out_dir.c_str());
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "shle: %s\n", e.what());
    return 1;
  }
}
