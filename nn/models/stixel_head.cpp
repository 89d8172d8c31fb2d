#include "nn/models/stixel_head.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "nn/activation.h"
#include "nn/error.h"
#include "nn/layernorm.h"

namespace nn {

namespace {

using Dims = std::vector<std::int64_t>;
constexpr float kLnEps = 1e-6f;
constexpr int kReducedV4 = 256;
constexpr int kReducedV0V3 = 3 * StixelHead::kCandidates;

AlignedBuffer to_buffer(const std::vector<float>& v) {
  AlignedBuffer b(v.size());
  std::copy(v.begin(), v.end(), b.data());
  return b;
}

std::string attention_key(const std::string& prefix, const char* which, const char* leaf) {
  return prefix + "attention_layer." + which + "_layer." + leaf;
}

bool has_attention(const weights::SafeTensors& st, const std::string& prefix) {
  return st.has(attention_key(prefix, "query", "weight"));
}

// V0 names are not fixed by the reference: find the one 1x1 conv [192, C, 1, 1] and
// the one norm [192] under the prefix by their shapes.
bool find_v0(const weights::SafeTensors& st, const std::string& prefix, int c, std::string* conv,
             std::string* norm) {
  int convs = 0, norms = 0;
  for (const auto& name : st.names()) {
    if (name.compare(0, prefix.size(), prefix) != 0) continue;
    if (name.size() < 7 || name.compare(name.size() - 7, 7, ".weight") != 0) continue;
    const std::string base = name.substr(0, name.size() - 7);
    if (!st.has(base + ".bias")) continue;
    const auto& s = st.info(name).shape;
    if (s == Dims{kReducedV0V3, c, 1, 1}) {
      *conv = base;
      ++convs;
    } else if (s == Dims{kReducedV0V3}) {
      *norm = base;
      ++norms;
    }
  }
  return convs == 1 && norms == 1;
}

// PyTorch's nearest rule for Upsample(size=...): src = min(floor(dst * (in / out)), in - 1)
// with the scale in float.
int nearest_source(int dst, int in, int out) {
  const float scale = static_cast<float>(in) / static_cast<float>(out);
  return std::min(static_cast<int>(std::floor(static_cast<float>(dst) * scale)), in - 1);
}

}  // namespace

const char* stixel_head_name(StixelHeadVariant v) {
  switch (v) {
    case StixelHeadVariant::V0: return "v0";
    case StixelHeadVariant::V1: return "v1";
    case StixelHeadVariant::V2: return "v2";
    case StixelHeadVariant::V3: return "v3";
    case StixelHeadVariant::V4: return "v4";
  }
  return "?";
}

bool parse_stixel_head(const std::string& text, StixelHeadVariant* out) {
  for (auto v : {StixelHeadVariant::V0, StixelHeadVariant::V1, StixelHeadVariant::V2, StixelHeadVariant::V3,
                 StixelHeadVariant::V4})
    if (text == stixel_head_name(v) || text == std::string("V") + stixel_head_name(v)[1]) {
      *out = v;
      return true;
    }
  return false;
}

StixelHeadVariant detect_stixel_head(const weights::SafeTensors& st, const std::string& prefix, int c) {
  if (st.has(prefix + "local_mixing.depthwise.weight")) return StixelHeadVariant::V4;
  if (st.has(prefix + "channel_reduce.weight")) {
    const auto& s = st.info(prefix + "channel_reduce.weight").shape;
    if (s.size() == 4 && s[1] == 2 * c) return StixelHeadVariant::V1;
    if (s.size() == 4 && s[1] == c) return has_attention(st, prefix) ? StixelHeadVariant::V2 : StixelHeadVariant::V0;
  }
  std::string conv, norm;
  if (find_v0(st, prefix, c, &conv, &norm)) return StixelHeadVariant::V0;
  const std::string cs = std::to_string(c), c2 = std::to_string(2 * c);
  throw weights::Error(
      st.source() + ": unknown stixel head layout under '" + prefix + "': expected V4 (" + prefix +
      "local_mixing.depthwise.weight [" + cs + ", 1, 1, 5], " + prefix + "shared_reduce.weight [256, " + cs +
      ", 1, 1], " + prefix + "geometry_head/depth_head/probability_head.weight), V1/V3 (" + prefix +
      "attention_layer.{query,key,value}_layer.weight [" + cs + ", " + cs + "], " + prefix +
      "channel_reduce.weight [192, " + c2 + ", 1, 1]), V2 (channel_reduce.weight [192, " + cs +
      ", 1, 1] with attention tensors) or V0 (one 1x1 conv [192, " + cs + ", 1, 1] and one LayerNorm [192])");
}

std::vector<weights::TensorSpec> stixel_head_tensor_specs(StixelHeadVariant variant, int c, const std::string& prefix,
                                                          const std::string& reduce, const std::string& norm) {
  const std::int64_t C = c;
  std::vector<weights::TensorSpec> specs;
  auto add = [&](const std::string& name, Dims shape) { specs.push_back({prefix + name, std::move(shape)}); };
  if (variant == StixelHeadVariant::V4) {
    add("local_mixing.depthwise.weight", {C, 1, 1, 5});
    add("local_mixing.depthwise.bias", {C});
    add("local_mixing.pointwise.weight", {C, C, 1, 1});
    add("local_mixing.pointwise.bias", {C});
    add("shared_reduce.weight", {kReducedV4, C, 1, 1});
    add("shared_reduce.bias", {kReducedV4});
    add("up.1.weight", {kReducedV4});
    add("up.1.bias", {kReducedV4});
    add("geometry_head.weight", {2 * StixelHead::kCandidates, kReducedV4, 1, 1});
    add("geometry_head.bias", {2 * StixelHead::kCandidates});
    add("depth_head.weight", {StixelHead::kCandidates, kReducedV4, 1, 1});
    add("depth_head.bias", {StixelHead::kCandidates});
    add("probability_head.weight", {StixelHead::kCandidates, kReducedV4, 1, 1});
    add("probability_head.bias", {StixelHead::kCandidates});
    return specs;
  }
  const bool attends = variant == StixelHeadVariant::V1 || variant == StixelHeadVariant::V3;
  if (attends || variant == StixelHeadVariant::V2)
    for (const char* which : {"query", "key", "value"}) {
      add(std::string("attention_layer.") + which + "_layer.weight", {C, C});
      add(std::string("attention_layer.") + which + "_layer.bias", {C});
    }
  add(reduce + ".weight", {kReducedV0V3, attends ? 2 * C : C, 1, 1});
  add(reduce + ".bias", {kReducedV0V3});
  add(norm + ".weight", {kReducedV0V3});
  add(norm + ".bias", {kReducedV0V3});
  return specs;
}

StixelHead::StixelHead(const weights::SafeTensors& st, const std::string& prefix, StixelHeadVariant variant,
                       int c)
    : variant_(variant), c_(c) {
  std::string reduce = "channel_reduce", norm = "up.1";
  if (variant == StixelHeadVariant::V4) {
    reduce = "shared_reduce";
  } else if (variant == StixelHeadVariant::V0 && !st.has(prefix + "channel_reduce.weight")) {
    std::string conv, ln;
    if (!find_v0(st, prefix, c, &conv, &ln))
      throw weights::Error(st.source() + ": no V0 stixel head under '" + prefix + "': expected one 1x1 conv [192, " +
                           std::to_string(c) + ", 1, 1] with bias and one LayerNorm [192]");
    reduce = conv.substr(prefix.size());
    norm = ln.substr(prefix.size());
  }
  reduced_ = variant == StixelHeadVariant::V4 ? kReducedV4 : kReducedV0V3;
  specs_ = stixel_head_tensor_specs(variant, c, prefix, reduce, norm);
  weights::check_tensors(st, specs_);

  // Dump names (PyTorch's module tree of the head, stixel_head_ref.py).
  name_dw_ = prefix + "local_mixing.depthwise";
  name_pw_ = prefix + "local_mixing.pointwise";
  name_mix_ = prefix + "local_mixing";
  name_reduce_ = prefix + reduce;
  name_norm_ = prefix + norm;
  if (norm.size() > 2 && norm.compare(norm.size() - 2, 2, ".1") == 0) {  // Sequential(Upsample, LayerNorm2d)
    name_up_ = prefix + norm.substr(0, norm.size() - 2);
    name_up0_ = name_up_ + ".0";
  }
  name_att_ = prefix + "attention_layer";
  name_q_ = name_att_ + ".query_layer";
  name_k_ = name_att_ + ".key_layer";
  name_v_ = name_att_ + ".value_layer";
  if (variant == StixelHeadVariant::V4)  // three 1x1 convs + sigmoids + cat in one GEMM
    output_covers_ = module_list(prefix, {"geometry_head", "depth_head", "probability_head"});

  auto f = [&](const std::string& name) { return st.f32(prefix + name); };
  if (variant == StixelHeadVariant::V4) {
    DwConvParams dp;
    dp.kh = 1, dp.kw = 5, dp.pad_h = 0, dp.pad_w = 2;
    mix_dw_ = DwConvWeights::pack(f("local_mixing.depthwise.weight").data(), f("local_mixing.depthwise.bias").data(),
                                  c, dp);
    mix_pw_ = GemmWeights::pack(f("local_mixing.pointwise.weight").data(), c, c);
    mix_pw_bias_ = to_buffer(f("local_mixing.pointwise.bias"));
    // The three heads read the same normalised features: one 256-wide product whose
    // output channels are already in the [vB, vT | d | P] order.
    std::vector<float> w, b;
    for (const char* h : {"geometry_head", "depth_head", "probability_head"}) {
      auto hw = f(std::string(h) + ".weight"), hb = f(std::string(h) + ".bias");
      w.insert(w.end(), hw.begin(), hw.end());
      b.insert(b.end(), hb.begin(), hb.end());
    }
    heads_ = GemmWeights::pack(w.data(), 4 * kCandidates, kReducedV4);
    heads_bias_ = to_buffer(b);
  }
  if (variant == StixelHeadVariant::V1 || variant == StixelHeadVariant::V3) {
    std::vector<float> w, b;
    for (const char* which : {"query", "key", "value"}) {
      auto qw = f(std::string("attention_layer.") + which + "_layer.weight");
      auto qb = f(std::string("attention_layer.") + which + "_layer.bias");
      w.insert(w.end(), qw.begin(), qw.end());
      b.insert(b.end(), qb.begin(), qb.end());
    }
    qkv_ = GemmWeights::pack(w.data(), 3 * c, c);
    qkv_bias_ = to_buffer(b);
  }
  const int reduce_in = (variant == StixelHeadVariant::V1 || variant == StixelHeadVariant::V3) ? 2 * c : c;
  reduce_ = GemmWeights::pack(f(reduce + ".weight").data(), reduced_, reduce_in);
  reduce_bias_ = to_buffer(f(reduce + ".bias"));
  ln_gamma_ = to_buffer(f(norm + ".weight"));
  ln_beta_ = to_buffer(f(norm + ".bias"));
}

std::size_t StixelHead::weight_bytes() const {
  return mix_pw_.bytes() + heads_.bytes() + qkv_.bytes() + reduce_.bytes();
}

void StixelHead::plan(int n, int w) {
  const std::size_t m = static_cast<std::size_t>(n) * w;
  a_.resize(m * std::max(3 * c_, 4 * kCandidates));
  b_.resize(m * 2 * c_);
  c_buf_.resize(m * reduced_);
  planned_n_ = n;
  planned_w_ = w;
}

// ColumnAttention: for column i, softmax over keys j of q_i . k_j / sqrt(C), then the
// weighted sum of v_j; V1 looks at j in [i - 1, i + 1], V3 at every column.
void StixelHead::attention(const float* qkv, int n, int w, float* out) const {
  const int c = c_;
  const float scale = std::sqrt(static_cast<float>(c));
  const bool local = variant_ == StixelHeadVariant::V1;
  double weights_buf[1024];
  for (int b = 0; b < n; ++b)
    for (int i = 0; i < w; ++i) {
      const int j0 = local ? std::max(0, i - 1) : 0, j1 = local ? std::min(w - 1, i + 1) : w - 1;
      const float* q = qkv + (static_cast<std::size_t>(b) * w + i) * 3 * c;
      double peak = -INFINITY;
      for (int j = j0; j <= j1; ++j) {
        const float* k = qkv + (static_cast<std::size_t>(b) * w + j) * 3 * c + c;
        double dot = 0;
        for (int ch = 0; ch < c; ++ch) dot += static_cast<double>(q[ch]) * k[ch];
        weights_buf[j - j0] = dot / scale;
        peak = std::max(peak, weights_buf[j - j0]);
      }
      double sum = 0;
      for (int j = j0; j <= j1; ++j) sum += (weights_buf[j - j0] = std::exp(weights_buf[j - j0] - peak));
      float* o = out + (static_cast<std::size_t>(b) * w + i) * 2 * c;
      for (int ch = 0; ch < c; ++ch) {
        double acc = 0;
        for (int j = j0; j <= j1; ++j)
          acc += weights_buf[j - j0] * qkv[(static_cast<std::size_t>(b) * w + j) * 3 * c + 2 * c + ch];
        o[ch] = static_cast<float>(acc / sum);
      }
    }
}

void StixelHead::forward(const ConstTensorView& pooled, int columns, float* out) {
  const int n = pooled.shape.n, w = pooled.shape.w, c = c_;
  if (pooled.shape.h != 1 || pooled.shape.c != c || n > planned_n_ || w != planned_w_)
    throw Error("stixel head: input does not match the planned shape");
  if (variant_ == StixelHeadVariant::V3 && w > 1024) throw Error("stixel head: more than 1024 feature columns");
  const int m = n * w;
  const float* features = pooled.data;
  float* result = c_buf_.data();  // [m, attributes * 64] after the sigmoid
  if (variant_ == StixelHeadVariant::V4) {
    // x + pointwise(GELU(depthwise_1x5(x)))
    dwconv(pooled, mix_dw_, TensorView{a_.data(), pooled.shape});
    if (dump_) dump_nhwc(dump_, name_dw_, ConstTensorView(a_.data(), pooled.shape));
    apply_act(Act::Gelu, a_.data(), static_cast<std::size_t>(m) * c);
    GemmEpilogue mix;
    mix.bias = mix_pw_bias_.data();
    mix.residual = features;
    mix.ldr = c;
    gemm(m, a_.data(), c, mix_pw_, b_.data(), c, mix);
    if (dump_) dump_local_mixing(n, w);
    GemmEpilogue red;
    red.bias = reduce_bias_.data();
    gemm(m, b_.data(), c, reduce_, c_buf_.data(), reduced_, red);
    if (dump_) dump_reduced(n, w, columns, false);
    layernorm(m, reduced_, c_buf_.data(), reduced_, c_buf_.data(), reduced_, ln_gamma_.data(), ln_beta_.data(), kLnEps);
    if (dump_) dump_reduced(n, w, columns, true);
    GemmEpilogue heads;
    heads.bias = heads_bias_.data();
    heads.act = Act::Sigmoid;
    gemm(m, c_buf_.data(), reduced_, heads_, a_.data(), 4 * kCandidates, heads);
    result = a_.data();
  } else {
    const float* reduce_in = features;
    int k = c;
    if (variant_ == StixelHeadVariant::V1 || variant_ == StixelHeadVariant::V3) {
      GemmEpilogue qkv;
      qkv.bias = qkv_bias_.data();
      gemm(m, features, c, qkv_, a_.data(), 3 * c, qkv);
      if (dump_) {
        dump_columns(name_q_, a_.data(), n, w, 3 * c, 0, c, false);
        dump_columns(name_k_, a_.data(), n, w, 3 * c, c, c, false);
        dump_columns(name_v_, a_.data(), n, w, 3 * c, 2 * c, c, false);
      }
      attention(a_.data(), n, w, b_.data());
      if (dump_) dump_columns(name_att_, b_.data(), n, w, 2 * c, 0, c, true);
      // [attention output, F] along channels
      for (int r = 0; r < m; ++r)
        std::memcpy(b_.data() + static_cast<std::size_t>(r) * 2 * c + c, features + static_cast<std::size_t>(r) * c,
                    sizeof(float) * c);
      reduce_in = b_.data();
      k = 2 * c;
    }
    GemmEpilogue red;
    red.bias = reduce_bias_.data();
    gemm(m, reduce_in, k, reduce_, c_buf_.data(), reduced_, red);
    if (dump_) dump_reduced(n, w, columns, false);
    layernorm(m, reduced_, c_buf_.data(), reduced_, c_buf_.data(), reduced_, ln_gamma_.data(), ln_beta_.data(), kLnEps);
    if (dump_) dump_reduced(n, w, columns, true);
    apply_act(Act::Sigmoid, c_buf_.data(), static_cast<std::size_t>(m) * reduced_);
  }
  // [m, A*64] -> [n, A, 64, columns], column u taking feature column floor(u * W' / U).
  const int channels = attributes() * kCandidates;
  for (int b = 0; b < n; ++b)
    for (int ch = 0; ch < channels; ++ch) {
      float* dst = out + (static_cast<std::size_t>(b) * channels + ch) * columns;
      for (int u = 0; u < columns; ++u)
        dst[u] = result[(static_cast<std::size_t>(b) * w + nearest_source(u, w, columns)) * channels + ch];
    }
}

void StixelHead::dump_local_mixing(int n, int w) {
  if (!dump_->wants(name_pw_) && !dump_->wants(name_mix_)) return;
  const int m = n * w;
  dump_mix_.resize(static_cast<std::size_t>(m) * c_);
  GemmEpilogue pw;
  pw.bias = mix_pw_bias_.data();
  gemm(m, a_.data(), c_, mix_pw_, dump_mix_.data(), c_, pw);
  const ConstTensorView v(dump_mix_.data(), Shape{n, 1, w, c_});
  dump_nhwc(dump_, name_pw_, v);
  dump_nhwc(dump_, name_mix_, v);  // LocalColumnMixing returns its pointwise conv's output
}

std::string StixelHead::dump_path() const {
  if (variant_ != StixelHeadVariant::V4) return "";
  return "the head's " + name_mix_ + " (= " + name_pw_ +
         ", whose product the engine fuses with the residual) computed a second time without the residual";
}

// The reduced features before (the 1x1 conv's output, then Upsample's) or after the
// LayerNorm (LayerNorm2d's and the `up` Sequential's output). LayerNorm works per column,
// so normalising W' columns and then copying them equals PyTorch's upsample-then-norm.
void StixelHead::dump_reduced(int n, int w, int columns, bool normalised) const {
  const float* rows = c_buf_.data();
  if (!normalised) {
    dump_nhwc(dump_, name_reduce_, ConstTensorView(rows, Shape{n, 1, w, reduced_}));
    if (!name_up0_.empty()) dump_upsampled(name_up0_, rows, n, w, reduced_, columns);
    return;
  }
  dump_upsampled(name_norm_, rows, n, w, reduced_, columns);
  if (!name_up_.empty()) dump_upsampled(name_up_, rows, n, w, reduced_, columns);
}

void StixelHead::dump_upsampled(const std::string& name, const float* rows, int n, int w, int k, int columns) const {
  if (!dump_->wants(name)) return;
  float* out = dump_->scratch(static_cast<std::size_t>(n) * k * columns);
  for (int b = 0; b < n; ++b)
    for (int ch = 0; ch < k; ++ch)
      for (int u = 0; u < columns; ++u)
        out[(static_cast<std::size_t>(b) * k + ch) * columns + u] =
            rows[(static_cast<std::size_t>(b) * w + nearest_source(u, w, columns)) * k + ch];
  dump_->tensor(name, {n, k, 1, columns}, out, "");
}

void StixelHead::dump_columns(const std::string& name, const float* rows, int n, int w, int ld, int c0, int k,
                              bool as_nchw) const {
  if (!dump_->wants(name)) return;
  float* out = dump_->scratch(static_cast<std::size_t>(n) * w * k);
  for (int b = 0; b < n; ++b)
    for (int x = 0; x < w; ++x)
      for (int ch = 0; ch < k; ++ch) {
        const float v = rows[(static_cast<std::size_t>(b) * w + x) * ld + c0 + ch];
        out[as_nchw ? (static_cast<std::size_t>(b) * k + ch) * w + x : (static_cast<std::size_t>(b) * w + x) * k + ch] = v;
      }
  if (as_nchw)
    dump_->tensor(name, {n, k, 1, w}, out, "");
  else
    dump_->tensor(name, {n, w, k}, out, "");
}

}  // namespace nn
