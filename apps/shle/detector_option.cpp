#include "apps/shle/detector_option.h"

#include <cstdio>

#include "nn/threads.h"
#include "shle/detectron2_box_source.h"

namespace shleapp {
namespace {

// "1,2" -> {1, 2}; empty for anything else or a label below `lowest`.
std::vector<int> parse_labels(const std::string& text, int lowest) {
  std::vector<int> out;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    std::size_t comma = text.find(',', pos);
    std::string part = text.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos);
    if (part.empty() || part.size() > 5 || part.find_first_not_of("0123456789") != std::string::npos) return {};
    const int v = std::stoi(part);
    if (v < lowest) return {};
    out.push_back(v);
    if (comma == std::string::npos) break;
    pos = comma + 1;
  }
  return out;
}

std::string join(const std::vector<int>& v) {
  std::string s;
  for (int l : v) s += (s.empty() ? "" : ",") + std::to_string(l);
  return s;
}

}  // namespace

void add_detector_options(cli::Parser& p, DetectorChoice* d, const std::string& prefix) {
  p.option("detector-weights", "W", prefix + "detector weights as .safetensors (--boxes detector)", &d->weights);
  p.option("detector-model", "NAME",
           prefix + "fasterrcnn_mobilenet_v3_large_fpn (default), fasterrcnn_mobilenet_v3_large_320_fpn, "
                    "fasterrcnn_resnet50_fpn or detectron2_faster_rcnn_r50_fpn (the released stage 1's "
                    "model_final.pth, converted by weights/export.py; its labels are 0-based)",
           &d->model);
  p.option("detector-score", "S", prefix + "detections with score > S are candidates (default 0.3)", &d->score);
  p.option("detector-labels", "L,..",
           prefix + "labels that are height-limit devices (default: every label but 0; detectron2: every class)",
           &d->labels);
  p.option("threads", "N", prefix + "threads for the detector (default: all cores)", &d->threads);
}

void check_detector_options(cli::Parser& p, bool used, DetectorChoice* d) {
  if (used) {
    if (d->weights.empty()) p.fail("--boxes detector needs --detector-weights W.safetensors");
    d->detectron2 = d->model == nn::detection::kDetectron2FasterRcnnName;
    if (!d->detectron2 && !nn::detection::parse_faster_rcnn(d->model, &d->variant))
      p.fail("--detector-model must be fasterrcnn_mobilenet_v3_large_fpn, fasterrcnn_mobilenet_v3_large_320_fpn, "
             "fasterrcnn_resnet50_fpn or detectron2_faster_rcnn_r50_fpn");
    if (!(d->score >= 0 && d->score < 1)) p.fail("--detector-score must be in [0, 1)");
    d->options.score_threshold = d->score;
    if (p.given("detector-labels")) {
      d->options.labels = parse_labels(d->labels, d->detectron2 ? 0 : 1);
      if (d->options.labels.empty())
        p.fail(d->detectron2 ? "--detector-labels takes detectron2's 0-based classes separated by commas, e.g. 0"
                             : "--detector-labels takes labels >= 1 separated by commas, e.g. 1,2");
    }
  } else {
    for (const char* o : {"detector-weights", "detector-model", "detector-score", "detector-labels"})
      if (p.given(o)) p.fail(std::string("--") + o + " needs --boxes detector");
  }
  if (p.given("threads")) {
    if (d->threads < 1 || d->threads > 1024) p.fail("--threads must be in 1..1024");
    nn::set_num_threads(d->threads);
  }
}

std::unique_ptr<shle::BoxSource> make_detector_source(const DetectorChoice& d, const char* program, bool quiet,
                                                      DetectorDescription* description) {
  if (d.detectron2) {
    auto s = std::make_unique<shle::Detectron2BoxSource>(d.weights, d.options);
    *description = {d.model, d.weights, s->num_classes(), s->labels(), d.score};
    if (!quiet)
      std::fprintf(stderr, "%s: detector %s, %d classes (score > %g), weights %s\n", program, d.model.c_str(),
                   s->num_classes(), d.score, d.weights.c_str());
    return s;
  }
  auto s = std::make_unique<shle::DetectorBoxSource>(d.weights, d.variant, d.options);
  const char* name = nn::detection::faster_rcnn_name(d.variant);
  *description = {name, d.weights, s->num_classes(), s->labels(), d.score};
  if (!quiet)
    std::fprintf(stderr, "%s: detector %s, %d classes (device labels %s, score > %g), weights %s\n", program, name,
                 s->num_classes(), join(s->labels()).c_str(), d.score, d.weights.c_str());
  return s;
}

}  // namespace shleapp
