// roadnn_model_*: loading (file or memory, the same validation), parameters, info.

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <set>
#include <system_error>

#include "api/handles.h"
#include "api/safetensors_file.h"
#include "api/status.h"
#include "nn/gemm_bf16.h"
#include "nn/winograd.h"
#include "stixel/anchors.h"
#include "stixel/model_file.h"
#include "weights/file_io.h"
#include "weights/tensor_spec.h"

namespace roadnn_api {

// A C caller may store any int in an enum field of roadnn_model_params, and in C++
// loading a value outside the enum's range is undefined (UBSan -fsanitize=enum
// reported it in tests/api), so the fields are read as ints and checked first.
template <class E>
int raw_enum(const E& e) {
  static_assert(sizeof(E) == sizeof(int), "C enums are int-sized here");
  int v;
  std::memcpy(&v, &e, sizeof v);
  return v;
}

bool is_detector(roadnn_model_kind kind) {
  return kind == ROADNN_MODEL_FASTERRCNN_MOBILENET_V3_LARGE_FPN ||
         kind == ROADNN_MODEL_FASTERRCNN_MOBILENET_V3_LARGE_320_FPN || kind == ROADNN_MODEL_FASTERRCNN_RESNET50_FPN;
}

bool is_known_kind(roadnn_model_kind kind) {
  return kind == ROADNN_MODEL_CONVNEXT || kind == ROADNN_MODEL_STIXELNEXT || is_detector(kind);
}

const char* kind_name(roadnn_model_kind kind) {
  switch (kind) {
    case ROADNN_MODEL_CONVNEXT: return "convnext";
    case ROADNN_MODEL_STIXELNEXT: return "stixelnext";
    case ROADNN_MODEL_FASTERRCNN_MOBILENET_V3_LARGE_FPN: return "fasterrcnn_mobilenet_v3_large_fpn";
    case ROADNN_MODEL_FASTERRCNN_MOBILENET_V3_LARGE_320_FPN: return "fasterrcnn_mobilenet_v3_large_320_fpn";
    case ROADNN_MODEL_FASTERRCNN_RESNET50_FPN: return "fasterrcnn_resnet50_fpn";
  }
  return "unknown";
}

namespace {

nn::detection::FasterRcnnVariant variant_of(roadnn_model_kind kind) {
  switch (kind) {
    case ROADNN_MODEL_FASTERRCNN_MOBILENET_V3_LARGE_320_FPN:
      return nn::detection::FasterRcnnVariant::MobileNetV3Large320Fpn;
    case ROADNN_MODEL_FASTERRCNN_RESNET50_FPN: return nn::detection::FasterRcnnVariant::ResNet50Fpn;
    default: return nn::detection::FasterRcnnVariant::MobileNetV3LargeFpn;
  }
}

nn::ExecOptions exec_of(const roadnn_model_params& p) {
  nn::ExecOptions e;
  switch (raw_enum(p.max_isa)) {
    case ROADNN_ISA_SCALAR: e.max_isa = nn::Isa::Scalar; break;
    case ROADNN_ISA_AVX2: e.max_isa = nn::Isa::Avx2; break;
    case ROADNN_ISA_AVX512: e.max_isa = nn::Isa::Avx512; break;
    case ROADNN_ISA_NEON: e.max_isa = nn::Isa::Neon; break;
    case ROADNN_ISA_BEST: e.max_isa = nn::detect_isa(); break;
    default:
      fail(ROADNN_ERROR_INVALID_ARGUMENT,
           "roadnn_model_params.max_isa " + std::to_string(raw_enum(p.max_isa)) + " is not a roadnn_isa");
  }
  e.max_isa = nn::cap_isa(e.max_isa);  // a cap: at most that level of what the CPU has
  if (p.winograd != 0 && p.winograd != 1)
    fail(ROADNN_ERROR_INVALID_ARGUMENT, "roadnn_model_params.winograd must be 0 or 1");
  e.winograd = p.winograd == 1;
  e.threads = 0;  // loading may pack on all cores
  return e;
}

nn::Precision precision_of(const roadnn_model_params& p) {
  const int precision = raw_enum(p.precision);
  if (precision == ROADNN_PRECISION_F32) return nn::Precision::F32;
  if (precision != ROADNN_PRECISION_BF16)
    fail(ROADNN_ERROR_INVALID_ARGUMENT, "roadnn_model_params.precision must be F32 or BF16");
  if (p.kind != ROADNN_MODEL_CONVNEXT && p.kind != ROADNN_MODEL_STIXELNEXT)
    fail(ROADNN_ERROR_INVALID_ARGUMENT, std::string("precision bf16 applies to ConvNeXt and StixelNExT++ only, not ") +
                                            kind_name(p.kind));
  if (!nn::bf16_gemm_available())
    fail(ROADNN_ERROR_UNSUPPORTED,
         "precision bf16 needs AVX512_BF16 and the avx512 kernels; this CPU (or max_isa) does not offer them");
  return nn::Precision::Bf16;
}

// The StixelNExT++ settings: the weights' metadata, then the caller's parameters.
stixel::ModelSettings stixel_settings_of(const roadnn_model_params& p, const weights::SafeTensors& st) {
  // The file's metadata, its declared head checked against its tensors.
  stixel::ModelSettings s = stixel::settings_from_weights(st);
  if (p.stixel_head != -1) {
    if (p.stixel_head < 0 || p.stixel_head > 4)
      fail(ROADNN_ERROR_INVALID_ARGUMENT, "roadnn_model_params.stixel_head must be -1 (detect) or 0..4");
    s.head = static_cast<nn::StixelHeadVariant>(p.stixel_head);
  }
  if (p.input_height != 0 || p.input_width != 0) {
    if (p.input_height < 32 || p.input_width < 32 || p.input_height > 16384 || p.input_width > 16384)
      fail(ROADNN_ERROR_INVALID_ARGUMENT, "roadnn_model_params.input_height/_width must both be in [32, 16384]");
    s.input_height = p.input_height;
    s.input_width = p.input_width;
  }
  if (p.stixel_width != 0) {
    if (p.stixel_width < 1 || p.stixel_width > 1024)
      fail(ROADNN_ERROR_INVALID_ARGUMENT, "roadnn_model_params.stixel_width must be in [1, 1024]");
    s.stixel_width = p.stixel_width;
  }
  if (p.columns != 0) {
    if (p.columns < 1 || p.columns > 16384)
      fail(ROADNN_ERROR_INVALID_ARGUMENT, "roadnn_model_params.columns must be in [1, 16384]");
    s.columns = p.columns;
  }
  if (p.anchors) {
    // A malformed spec is the caller's argument, not the weights' fault.
    try {
      s.anchors = stixel::parse_anchor_spec(p.anchors, "roadnn_model_params.anchors");
    } catch (const std::exception& e) {
      fail(ROADNN_ERROR_INVALID_ARGUMENT, e.what());
    }
  }
  if (p.normalization && !stixel::parse_normalization(p.normalization, &s.normalization))
    fail(ROADNN_ERROR_INVALID_ARGUMENT, "roadnn_model_params.normalization must be raw255, unit or imagenet");
  if (s.effective_columns() < 1)
    fail(ROADNN_ERROR_INVALID_ARGUMENT, "the stixel width is wider than the network input");
  s.precision = precision_of(p);
  return s;
}

void warn_unused(roadnn_model* m, const weights::SafeTensors& st, const std::vector<std::string>& used) {
  const std::string w = weights::unused_tensors_warning(st, used, kind_name(m->kind));
  if (!w.empty()) m->warnings.push_back(w);
}

std::size_t tensor_bytes(const weights::SafeTensors& st, const std::vector<weights::TensorSpec>& specs) {
  std::size_t bytes = 0;
  for (const auto& s : specs) bytes += st.info(s.name).end - st.info(s.name).begin;
  return bytes;
}

std::unique_ptr<roadnn_model> load(const weights::SafeTensors& st, const roadnn_model_params& p) {
  const int kind = raw_enum(p.kind);
  if (kind != ROADNN_MODEL_CONVNEXT && kind != ROADNN_MODEL_STIXELNEXT &&
      kind != ROADNN_MODEL_FASTERRCNN_MOBILENET_V3_LARGE_FPN &&
      kind != ROADNN_MODEL_FASTERRCNN_MOBILENET_V3_LARGE_320_FPN && kind != ROADNN_MODEL_FASTERRCNN_RESNET50_FPN)
    fail(ROADNN_ERROR_INVALID_ARGUMENT,
         "roadnn_model_params.kind " + std::to_string(kind) + " is not a roadnn_model_kind");
  // From here on p.kind is a valid roadnn_model_kind.
  if (!(p.box_score_thresh < 0 || (p.box_score_thresh >= 0 && p.box_score_thresh <= 1)))
    fail(ROADNN_ERROR_INVALID_ARGUMENT, "roadnn_model_params.box_score_thresh must be < 0 (default) or in [0, 1]");
  auto m = std::make_unique<roadnn_model>();
  m->kind = p.kind;
  m->exec = exec_of(p);
  nn::ExecScope scope(m->exec);  // packing sees the model's ISA cap and Winograd choice
  if (p.kind == ROADNN_MODEL_CONVNEXT) {
    auto model = std::make_shared<const nn::ConvNeXt>(st, "features.", precision_of(p));
    std::vector<std::string> used;
    for (const auto& s : nn::convnext_tensor_specs(model->config(), "features.")) used.push_back(s.name);
    warn_unused(m.get(), st, used);
    m->weight_bytes = model->weight_bytes();
    m->convnext = std::move(model);
  } else if (p.kind == ROADNN_MODEL_STIXELNEXT) {
    m->stixel_settings = stixel_settings_of(p, st);
    auto model = std::make_shared<const nn::StixelNExT>(st, m->stixel_settings.head, m->stixel_settings.precision);
    if (m->stixel_settings.anchors.size() != nn::StixelHead::kCandidates)
      fail(ROADNN_ERROR_INVALID_ARGUMENT, "the head predicts 64 candidates but the anchor set has " +
                                              std::to_string(m->stixel_settings.anchors.size()));
    const std::string ambiguous = stixel::head_ambiguity_warning(st, m->stixel_settings.head);
    if (!ambiguous.empty()) m->warnings.push_back(ambiguous);
    m->stixel_settings.head = model->head().variant();
    warn_unused(m.get(), st, model->used_tensors());
    m->weight_bytes = model->backbone().weight_bytes() + model->head().weight_bytes();
    m->stixelnext = std::move(model);
  } else {
    precision_of(p);  // rejects bf16 (and values that are no roadnn_precision) for detectors
    const auto v = variant_of(p.kind);
    nn::detection::FasterRcnnConfig cfg = nn::detection::faster_rcnn_defaults(v);
    if (p.box_score_thresh >= 0) cfg.roi_heads.score_thresh = p.box_score_thresh;
    auto model = std::make_shared<const nn::detection::FasterRcnn>(st, v, cfg);
    std::vector<std::string> used;
    for (const auto& s : model->tensor_specs()) used.push_back(s.name);
    warn_unused(m.get(), st, used);
    m->weight_bytes = tensor_bytes(st, model->tensor_specs());
    m->detector = std::move(model);
  }
  return m;
}

roadnn_status load_guarded(const char* function, roadnn_model** out, const roadnn_model_params* params,
                           const std::function<weights::SafeTensors()>& read) {
  if (out) *out = nullptr;
  return guarded(ROADNN_ERROR_BAD_MODEL, [&] {
    require(out, function, "out");
    require(params, function, "params");
    weights::SafeTensors st = read();
    *out = load(st, *params).release();
  });
}

}  // namespace
}  // namespace roadnn_api

using namespace roadnn_api;

extern "C" {

roadnn_model_params roadnn_model_default_params(roadnn_model_kind kind) {
  roadnn_model_params p;
  p.kind = kind;
  p.max_isa = ROADNN_ISA_BEST;
  p.winograd = 1;
  p.precision = ROADNN_PRECISION_F32;
  p.stixel_head = -1;
  p.input_height = p.input_width = 0;
  p.columns = p.stixel_width = 0;
  p.anchors = nullptr;
  p.normalization = nullptr;
  p.box_score_thresh = -1.0f;
  return p;
}

roadnn_status roadnn_model_load_file(const char* path, const roadnn_model_params* params, roadnn_model** out) {
  return load_guarded("roadnn_model_load_file", out, params, [&] {
    require(path, "roadnn_model_load_file", "path");
    return load_safetensors_file(path);
  });
}

roadnn_status roadnn_model_load_memory(const void* data, size_t size, const roadnn_model_params* params,
                                       roadnn_model** out) {
  return load_guarded("roadnn_model_load_memory", out, params, [&] {
    require(data, "roadnn_model_load_memory", "data");
    if (size == 0) fail(ROADNN_ERROR_INVALID_ARGUMENT, "roadnn_model_load_memory: size is 0");
    const auto* bytes = static_cast<const std::uint8_t*>(data);
    return weights::SafeTensors::from_bytes(std::vector<std::uint8_t>(bytes, bytes + size), "<memory>");
  });
}

void roadnn_model_free(roadnn_model* model) { delete model; }

roadnn_status roadnn_model_get_info(const roadnn_model* model, roadnn_model_info* out) {
  return guarded(ROADNN_ERROR_INVALID_ARGUMENT, [&] {
    require(model, "roadnn_model_get_info", "model");
    require(out, "roadnn_model_get_info", "out");
    roadnn_model_info info;
    info.kind = model->kind;
    info.kernels = nn::isa_name(model->exec.max_isa);
    info.weight_bytes = model->weight_bytes;
    info.num_classes = model->detector ? model->detector->num_classes() : 0;
    info.input_height = model->stixelnext ? model->stixel_settings.input_height : 0;
    info.input_width = model->stixelnext ? model->stixel_settings.input_width : 0;
    info.columns = model->stixelnext ? model->stixel_settings.effective_columns() : 0;
    info.stixel_head = model->stixelnext ? nn::stixel_head_name(model->stixelnext->head().variant()) : "";
    const nn::ConvNeXtConfig* backbone = model->convnext      ? &model->convnext->config()
                                         : model->stixelnext ? &model->stixelnext->backbone().config()
                                                             : nullptr;
    for (int i = 0; i < 4; ++i) {
      const bool has = backbone && i < static_cast<int>(backbone->dims.size());
      info.stage_widths[i] = has ? backbone->dims[i] : 0;
      info.stage_depths[i] = has ? backbone->depths[i] : 0;
    }
    *out = info;
  });
}

size_t roadnn_model_warning_count(const roadnn_model* model) { return model ? model->warnings.size() : 0; }

const char* roadnn_model_warning(const roadnn_model* model, size_t index) {
  if (!model || index >= model->warnings.size()) return nullptr;
  return model->warnings[index].c_str();
}

}  // extern "C"
