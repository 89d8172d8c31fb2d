// nnrun: runs one model of the engine on tensors from a safetensors file and writes
// its outputs to another, as the PyTorch reference module would produce them.
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <exception>
#include <memory>
#include <regex>
#include <stdexcept>
#include <string>
#include <vector>

#include "apps/common/cli.h"
#include "apps/common/exec_env.h"
#include "apps/common/image_io.h"
#include "apps/common/output_files.h"
#include "apps/common/precision_option.h"
#include "apps/common/unused_tensors.h"
#include "apps/nnrun/detector_runner.h"
#include "apps/nnrun/dump_file.h"
#include "apps/nnrun/profile_report.h"
#include "apps/nnrun/runner.h"
#include "nn/isa.h"
#include "nn/peak.h"
#include "nn/threads.h"
#include "nn/winograd.h"
#include "weights/safetensors.h"

namespace nnrun {

const std::vector<ModelInfo>& models() {
  static const std::vector<ModelInfo> list = {
      {"convnext_tiny", "torchvision convnext_tiny().features: input [N,3,H,W] -> features [N,768,H/32,W/32]", make_convnext, true,
       make_convnext_api},
      {"convnext_small", "torchvision convnext_small().features", make_convnext, true, make_convnext_api},
      {"convnext_base", "torchvision convnext_base().features", make_convnext, true, make_convnext_api},
      {"convnext", "any ConvNeXt features configuration (widths and depths read from the weights)", make_convnext, true, make_convnext_api},
      {"stixelnext",
       "StixelNExT++ network (the authors' model): input [N,3,H,W] as the weights expect it (raw 0..255)\n"
       "      -> prediction [N,A,64,U] after the sigmoid (A = 4 for head v4, else 3); U and the head from the\n"
       "      weights' stixelnext.columns / stixel_width / head metadata (default U = W / 8)",
       make_stixelnext, true, nullptr},
      {"fasterrcnn_mobilenet_v3_large_fpn",
       "torchvision Faster R-CNN, MobileNetV3-Large FPN: input [1,3,H,W] RGB in [0,1] -> boxes [K,4], scores [K], "
       "labels [K] (I64) in input pixels",
       make_detector, false, nullptr},
      {"fasterrcnn_mobilenet_v3_large_320_fpn", "the same at 320/640 px (torchvision's low-resolution defaults)",
       make_detector, false, nullptr},
      {"fasterrcnn_resnet50_fpn", "torchvision Faster R-CNN, ResNet-50 FPN (v1): same input and outputs", make_detector, false, nullptr},
      {"detectron2_faster_rcnn_r50_fpn",
       "detectron2's Faster R-CNN R50-FPN (SHLE's model_final.pth via weights/export.py): --image FILE or input\n"
       "                            'input' U8 [H,W,3] RGB -> boxes [K,4] (original pixels), scores [K], classes [K] I64\n"
       "                            (0-based)",
       make_detectron2, false, nullptr},
  };
  return list;
}

}  // namespace nnrun

namespace {

// Peak resident memory of this program, in MB. Linux's ru_maxrss carries over the
// high-water mark of the process that forked us (a Python driver with torch loaded
// reports its own gigabyte), so read VmHWM of our own address space first.
double peak_rss_mb() {
  if (std::FILE* f = std::fopen("/proc/self/status", "r")) {
    char line[256];
    long kb = -1;
    while (std::fgets(line, sizeof line, f))
      if (std::sscanf(line, "VmHWM: %ld kB", &kb) == 1) break;
    std::fclose(f);
    if (kb >= 0) return kb / 1024.0;
  }
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return ru.ru_maxrss / 1024.0;
}

}  // namespace

int main(int argc, char** argv) {
  apps::apply_exec_environment("nnrun");
  std::string model, weights_path, input_path, image_path, output_path, isa_name, precision_name, conv3x3;
  std::string dump_path, dump_filter, format = "table", profile_out;
  int threads = 0, repeat = 0, warmup = 0;
  bool profile = false, quiet = false, dump_proposals = false;

  std::string model_list = "models:\n";
  for (const auto& m : nnrun::models()) model_list += "  " + std::string(m.name) + "\n      " + m.help + "\n";
  cli::Parser args("nnrun", "--model NAME --weights W.safetensors --input X.safetensors --output Y.safetensors [options]",
                   "Runs a model of the engine on the tensors in X and writes its outputs to Y, exactly as\n"
                   "the PyTorch reference module computes them (NCHW at the boundary).");
  args.option("model", "NAME", "model to run (see the list below)", &model);
  args.option("weights", "FILE", "weights as safetensors, PyTorch state_dict names", &weights_path);
  args.option("input", "FILE", "input tensors as safetensors (e.g. 'input' [N,3,H,W] F32)", &input_path);
  args.option("image", "FILE", "instead of --input: an image file (PNG, JPEG, BMP) for the models that take one\n"
              "                            (detectron2_faster_rcnn_r50_fpn)", &image_path);
  args.option("output", "FILE", "where to write the output tensors (safetensors)", &output_path);
  args.option("threads", "N", "threads (default: all cores)", &threads);
  args.option("repeat", "R", "run the forward pass R more times; print peak_rss_mb= and, last,\n"
              "                            forward_ms min=.. median=.. max=.. (forward only, no loading or I/O)", &repeat);
  args.option("warmup", "N", "with --repeat or --profile: N more untimed passes before the timed ones (default 0;\n"
              "                            the first pass, which writes --output, is never timed)", &warmup);
  args.flag("profile", "print a per-layer time table (mean over the timed passes)", &profile);
  args.option("format", "F", "--profile output: table (default, for people), json or csv: per layer the PyTorch\n"
              "                            module name (as --dump names it), op, shape, FLOPs, bytes moved, ms min/median/max\n"
              "                            over the timed calls, GFLOP/s and percent of the FMA peak measured in this run",
              &format);
  args.option("profile-out", "FILE", "write the --profile json/csv there instead of to stdout", &profile_out);
  args.option("dump", "FILE", "also write every intermediate tensor of the first forward pass that has a PyTorch\n"
              "                            counterpart, under its module name and in PyTorch's layout (safetensors; see\n"
              "                            docs/NUMERICS.md for the names and the dump.* metadata)", &dump_path);
  args.option("dump-filter", "REGEX", "--dump only the tensors whose names contain a match of REGEX (ECMAScript)",
              &dump_filter);
  args.option("isa", "NAME", "force a kernel set: scalar, avx2, avx512 (x86-64) or neon (aarch64) (default: best available)", &isa_name);
  args.option("precision", "P", std::string("ConvNeXt models: ") + apps::kPrecisionHelp, &precision_name);
  args.option("conv3x3", "ALGO", "3x3 stride-1 convolutions (detectors): winograd (default; F(4x4,3x3), a quarter\n"
              "                            of the multiply-adds) or direct (im2col; rounds as closely to PyTorch as the\n"
              "                            other layers). The environment's NN_WINOGRAD=0 also selects direct",
              &conv3x3);
  args.flag("dump-proposals", "detectors: also write the RPN proposals ('proposals' [P,4], 'proposal_scores' [P],\n"
            "                            in the pixels of the resized image 'proposal_image_size' [2] = H,W)",
            &dump_proposals);
  args.flag("quiet", "print only errors and the timing line", &quiet);
  for (const char* r : {"model", "weights", "output"}) args.required(r);
  args.epilog(model_list +
              "\nexample:\n  nnrun --model convnext_tiny --weights convnext_tiny.safetensors \\\n"
              "        --input x.safetensors --output y.safetensors --threads 2 --repeat 5\n"
              "  nnrun --model convnext_tiny ... --dump d.safetensors --dump-filter '^features\\.[0-9]+$'\n"
              "  nnrun --model convnext_tiny ... --profile --repeat 10 --format json --profile-out t.json\n"
              "  nnrun --model detectron2_faster_rcnn_r50_fpn --weights model_final.safetensors \\\n"
              "        --image frame.png --output d.safetensors --dump-proposals");
  args.parse(argc, argv);

  const nnrun::ModelInfo* info = nullptr;
  for (const auto& m : nnrun::models())
    if (model == m.name) info = &m;
  if (!info) args.fail("unknown model '" + model + "'");
  if (repeat < 0) args.fail("--repeat must be >= 0");
  if (warmup < 0) args.fail("--warmup must be >= 0");
  if (warmup > 0 && repeat == 0 && !profile) args.fail("--warmup needs --repeat or --profile");
  if (input_path.empty() == image_path.empty()) args.fail("give one of --input FILE and --image FILE");
  for (const std::string* p : {&weights_path, &output_path})
    if (p->empty()) args.fail("--weights and --output must not be empty");
  if (format != "table" && format != "json" && format != "csv") args.fail("--format must be table, json or csv");
  if (format != "table" && !profile) args.fail("--format " + format + " needs --profile");
  if (!profile_out.empty() && format == "table") args.fail("--profile-out needs --profile --format json or csv");
  if (!dump_filter.empty() && dump_path.empty()) args.fail("--dump-filter needs --dump FILE");
  std::unique_ptr<nnrun::DumpFile> dump;
  if (!dump_path.empty()) {
    try {
      dump = std::make_unique<nnrun::DumpFile>(model, dump_filter);
    } catch (const std::regex_error& e) {
      args.fail("--dump-filter '" + dump_filter + "' is not a valid regular expression (" + e.what() + ")");
    }
  }
  if (threads < 0) args.fail("--threads must be >= 0");
  if (!isa_name.empty()) {
    nn::Isa isa;
    if (!nn::parse_isa(isa_name.c_str(), &isa)) args.fail("--isa must be scalar, avx2, avx512 or neon");
    if (!nn::isa_supported(isa))
      args.fail(std::string("--isa ") + isa_name + ": this build and CPU do not support it; the best they have is " + nn::isa_name(nn::detect_isa()));
    nn::set_isa(isa);
  }
  if (!conv3x3.empty()) {
    if (conv3x3 != "winograd" && conv3x3 != "direct") args.fail("--conv3x3 must be winograd or direct");
    nn::set_winograd(conv3x3 == "winograd");
  }
  nn::set_num_threads(threads);
  nnrun::RunOptions options;
  options.precision = apps::precision_option(args, precision_name);
  if (options.precision != nn::Precision::F32 && !info->has_precision)
    args.fail("--precision " + precision_name + ": model '" + model + "' runs in f32 only (ConvNeXt models have bf16)");

  try {
    // Before anything is read or written: the output must not replace an input.
    outputs::Plan plan;
    plan.input(weights_path, "weights");
    plan.input(image_path.empty() ? input_path : image_path, image_path.empty() ? "input" : "image");
    plan.output(output_path);
    if (dump) plan.output(dump_path);
    if (!profile_out.empty()) plan.output(profile_out);
    plan.check();
    outputs::install_interrupt_cleanup();

    std::unique_ptr<nnrun::Runner> runner;
    if (info->make_api && !profile) {
      // A plain run: through the public API, as an embedder would run the model.
      options.max_isa = nn::active_isa();
      options.threads = threads;
      runner = info->make_api(model, weights_path, options);
      for (const std::string& w : runner->warnings()) std::fprintf(stderr, "nnrun: warning: %s\n", w.c_str());
    } else {
      // The file's bytes are released once the model has repacked them.
      weights::SafeTensors w = weights::SafeTensors::load(weights_path);
      runner = info->make(model, w, options);
      apps::warn_unused_tensors("nnrun", w, runner->used_tensors(), model);
    }
    if (dump_proposals && !runner->enable_proposal_dump())
      args.fail("--dump-proposals: model '" + model + "' has no region proposals (detectors only)");
    if (!image_path.empty()) {
      if (!runner->takes_image()) args.fail("--image: model '" + model + "' takes --input tensors, not an image");
      const imageio::Image img = imageio::load(image_path, 3);
      runner->prepare_rgb8(img.u8.data(), img.height, img.width, image_path);
    } else {
      weights::SafeTensors x = weights::SafeTensors::load(input_path);
      runner->prepare(x);
    }
    if (!quiet)
      std::fprintf(stderr, "nnrun: %s: %s; kernels %s, %d threads%s\n", model.c_str(), runner->describe().c_str(),
                   nn::isa_name(nn::active_isa()), nn::num_threads(),
                   nn::winograd_enabled() ? "" : ", 3x3 convolutions direct");

    if (dump) {
      runner->set_dump(dump.get());
      dump->set_path(runner->dump_path());
    }
    runner->forward();
    if (dump) {
      runner->set_dump(nullptr);  // the timed passes below run without it
      if (dump->count() == 0)
        throw std::runtime_error("--dump-filter '" + dump_filter + "' matches none of the tensors model '" + model +
                                 "' dumps (nothing written)");
    }
    weights::Writer out;
    out.set_metadata("format", "roadnn-v1");
    out.set_metadata("model", model);
    runner->write_outputs(out);
    out.write(output_path, &outputs::temporary_file_hooks());
    if (dump) dump->write(dump_path);

    if (repeat > 0 || profile) {
      for (int i = 0; i < warmup; ++i) runner->forward();
      if (nn::Profiler* table = runner->profiler()) {
        table->set_enabled(profile);
        table->reset_times();
      }
      nn::Profiler* layers = runner->layer_profiler();
      if (layers) {
        layers->set_enabled(profile);
        layers->reset_times();
      }
      std::vector<double> ms;
      const int passes = std::max(repeat, 1);
      // Per-call samples for min/median/max, room made before the timed passes.
      for (nn::Profiler* p : {runner->profiler(), layers})
        if (p && profile) p->reserve_samples(passes);
      for (int i = 0; i < passes; ++i) {
        auto t0 = std::chrono::steady_clock::now();
        runner->forward();
        ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
      }
      // Machine-readable output on stdout takes stdout alone; the text lines go to stderr.
      std::FILE* text = (profile && format != "table" && profile_out.empty()) ? stderr : stdout;
      if (profile && format == "table") {
        std::fputs(runner->profiler()->table().c_str(), stdout);
        if (layers) std::printf("\nby layer:\n%s", layers->table().c_str());
      } else if (profile) {
        nnrun::ProfileRun run;
        run.model = model;
        run.isa = nn::isa_name(nn::active_isa());
        run.threads = nn::num_threads();
        run.passes = passes;
        run.forward_min = *std::min_element(ms.begin(), ms.end());
        run.forward_median = nnrun::median_of(ms);
        run.forward_max = *std::max_element(ms.begin(), ms.end());
        run.peak_gflops = nn::peak_gflops(run.threads);  // after the timed passes, same process
        std::vector<nnrun::ProfileTable> tables{{runner->profiler(), "model"}};
        if (layers) tables.push_back({layers, "layer"});
        const std::string report =
            format == "json" ? nnrun::profile_json(run, tables) : nnrun::profile_csv(run, tables);
        if (profile_out.empty())
          std::fputs(report.c_str(), stdout);
        else
          outputs::write_file(profile_out, report.data(), report.size());
      }
      if (repeat > 0) std::fprintf(text, "peak_rss_mb=%.1f\n", peak_rss_mb());
      if (repeat > 0)
        std::fprintf(text, "forward_ms min=%.3f median=%.3f max=%.3f\n", *std::min_element(ms.begin(), ms.end()),
                     nnrun::median_of(ms), *std::max_element(ms.begin(), ms.end()));
    }
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "nnrun: out of memory\n");
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "nnrun: %s\n", e.what());
    return 1;
  }
  return 0;
}
