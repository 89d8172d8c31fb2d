#include "stixel/model_file.h"

#include <cstdlib>

#include "nn/models/convnext.h"
#include "stixel/error.h"
#include "weights/quote_name.h"

namespace stixel {
namespace {

const char* const kPrefix = "classifier.";

struct Preset {
  const char* name;
  std::map<std::string, std::string> metadata;
};

// The published setups (reference stixelnext.md §0, §1.2). weights/export.py
// writes the same keys; ExportPresetsAreTheLibrarys compares the two.
const std::vector<Preset>& presets() {
  static const std::vector<Preset> table = {
      {"waymo",
       {{"stixelnext.input_height", "1280"},
        {"stixelnext.input_width", "1920"},
        {"stixelnext.columns", "240"},
        {"stixelnext.stixel_width", "8"},
        {"stixelnext.normalization", "raw255"},
        {"stixelnext.anchors", "tangent:4,66,64"}}},
      {"coopscenes",
       {{"stixelnext.input_height", "1200"},
        {"stixelnext.input_width", "1920"},
        {"stixelnext.columns", "120"},
        {"stixelnext.stixel_width", "16"},
        {"stixelnext.normalization", "imagenet"},
        {"stixelnext.anchors", "tangent:4,66,64"}}},
  };
  return table;
}

int metadata_int(const std::map<std::string, std::string>& md, const std::string& key, int fallback, int lo, int hi,
                 const std::string& source) {
  auto it = md.find(key);
  if (it == md.end()) return fallback;
  char* end = nullptr;
  const long v = std::strtol(it->second.c_str(), &end, 10);
  if (it->second.empty() || *end || v < lo || v > hi)
    throw Error(source + ": metadata " + key + "=" + weights::quote_name(it->second) + " is not an integer in [" +
                std::to_string(lo) + ", " + std::to_string(hi) + "]");
  return static_cast<int>(v);
}

int backbone_channels(const weights::SafeTensors& st) { return nn::convnext_config_from(st, "features.").dims.back(); }

bool fits(nn::StixelHeadVariant declared, nn::StixelHeadVariant layout) {
  using V = nn::StixelHeadVariant;
  return declared == layout || (layout == V::V1 && declared == V::V3);
}

std::string layout_name(nn::StixelHeadVariant layout) {
  return layout == nn::StixelHeadVariant::V1 ? "v1/v3" : nn::stixel_head_name(layout);
}

// The tensor that shows the contradiction: the first one the declared head needs
// that is missing or has another shape, else the first one the file's own head
// has that the declared one does not.
std::string disagreeing_tensor(const weights::SafeTensors& st, nn::StixelHeadVariant declared,
                               nn::StixelHeadVariant layout, int c) {
  const std::string name = nn::stixel_head_name(declared);
  const auto want = nn::stixel_head_tensor_specs(declared, c, kPrefix);
  for (const auto& spec : want) {
    if (!st.has(spec.name)) return spec.name + " is missing (a " + name + " head needs it)";
    const auto& shape = st.info(spec.name).shape;
    if (shape != spec.shape)
      return spec.name + " is " + weights::shape_str(shape) + " where a " + name + " head needs " +
             weights::shape_str(spec.shape);
  }
  for (const auto& spec : nn::stixel_head_tensor_specs(layout, c, kPrefix)) {
    bool wanted = false;
    for (const auto& w : want) wanted = wanted || w.name == spec.name;
    if (!wanted && st.has(spec.name)) return spec.name + " is present, which a " + name + " head does not have";
  }
  return "the tensors under " + std::string(kPrefix) + " are not a " + name + " head";
}

}  // namespace

std::vector<std::string> preset_names() {
  std::vector<std::string> names;
  for (const auto& p : presets()) names.push_back(p.name);
  return names;
}

bool preset_metadata(const std::string& name, std::map<std::string, std::string>* out) {
  for (const auto& p : presets())
    if (name == p.name) {
      *out = p.metadata;
      return true;
    }
  return false;
}

void apply_metadata(const std::map<std::string, std::string>& md, const std::string& source, ModelSettings* s) {
  s->input_height = metadata_int(md, "stixelnext.input_height", s->input_height, 32, 16384, source);
  s->input_width = metadata_int(md, "stixelnext.input_width", s->input_width, 32, 16384, source);
  s->stixel_width = metadata_int(md, "stixelnext.stixel_width", s->stixel_width, 1, 1024, source);
  s->columns = metadata_int(md, "stixelnext.columns", s->columns, 1, 16384, source);
  if (auto it = md.find("stixelnext.anchors"); it != md.end())
    s->anchors = parse_anchor_spec(it->second, source + ": metadata stixelnext.anchors");
  if (auto it = md.find("stixelnext.normalization"); it != md.end() && !parse_normalization(it->second, &s->normalization))
    throw Error(source + ": metadata stixelnext.normalization=" + weights::quote_name(it->second) +
                " is not raw255, unit or imagenet");
  if (auto it = md.find("stixelnext.head"); it != md.end()) {
    nn::StixelHeadVariant v;
    if (!nn::parse_stixel_head(it->second, &v))
      throw Error(source + ": metadata stixelnext.head=" + weights::quote_name(it->second) + " is not one of v0..v4");
    s->head = v;
  }
}

nn::StixelHeadVariant head_layout(const weights::SafeTensors& st) {
  return nn::detect_stixel_head(st, kPrefix, backbone_channels(st));
}

ModelSettings settings_from_weights(const weights::SafeTensors& st) {
  ModelSettings s = settings_from_metadata(st.metadata(), st.source());
  if (s.head) {
    const int c = backbone_channels(st);
    const nn::StixelHeadVariant layout = nn::detect_stixel_head(st, kPrefix, c);
    if (!fits(*s.head, layout))
      throw Error(st.source() + ": metadata stixelnext.head=" + nn::stixel_head_name(*s.head) +
                  " contradicts the tensors, which are a " + layout_name(layout) + " head: " +
                  disagreeing_tensor(st, *s.head, layout, c));
  }
  return s;
}

std::string head_ambiguity_warning(const weights::SafeTensors& st, const std::optional<nn::StixelHeadVariant>& head) {
  if (head) return "";
  if (head_layout(st) != nn::StixelHeadVariant::V1) return "";
  return st.source() +
         ": the head's tensors fit both V1 (column attention over the neighbouring columns) and V3 (attention over "
         "all columns), and nothing says which: running as V1. Say which with --head v1 or --head v3 "
         "(roadnn_model_params.stixel_head 1 or 3), or once in the file: weights/export.py FILE OUT "
         "--meta stixelnext.head=v1 (or v3)";
}

}  // namespace stixel
