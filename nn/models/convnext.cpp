#include "nn/models/convnext.h"

#include <algorithm>
#include <chrono>
#include <cstring>

#include "nn/activation.h"
#include "nn/error.h"
#include "nn/layernorm.h"
#include "nn/layout.h"
#include "nn/threads.h"

namespace nn {

namespace {

constexpr int kMlpTile = 64;  // rows of the fused LN -> pw1 -> GELU -> pw2 tile
// Rows of that tile when the block's weights are too large to stay cached between tiles.
constexpr int kMlpWideTile = 256;
constexpr double kMlpCachedWeightBytes = 8e6;
// Image rows per band of a block's depthwise -> MLP (run_block_banded). At 1280x1920 on
// Zen 5 (2 threads, 6-8 alternating nnrun rounds, medians of the stage sums) bands of 8
// rows took 1231 ms against 1249 for 4 and 1227 for 16; 8 needs half the scratch of 16.
constexpr int kDwMlpBand = 8;

std::size_t round_up_floats(std::size_t floats) { return (floats + 15) / 16 * 16; }  // 64 bytes

std::string join(const std::vector<int>& v) {
  std::string s = "[";
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + std::to_string(v[i]);
  return s + "]";
}

AlignedBuffer load_vec(const weights::SafeTensors& st, const std::string& name) {
  std::vector<float> v = st.f32(name);
  AlignedBuffer b(v.size());
  std::copy(v.begin(), v.end(), b.data());
  return b;
}

// Rows per tile of the fused MLP (LN -> pw1 -> GELU -> pw2 with the hidden tile in
// cache), or 0 for the layer-by-layer path, whose GEMMs split columns over the threads.
// Many rows: 64-row tiles. Each tile streams all of the block's weights (8 c^2 floats),
// so where they are too large to stay in the L3 between tiles (stage 4: 19 MB, on a
// 32 MB L3 shared with other tenants) tiles of 256 rows stream them a quarter as often:
// stage 4 at 1280x1920 went from 202 to 189 ms (medians of 8 alternating nnrun rounds,
// Zen 5, 2 threads); 128-row tiles for stage 3's 4.7 MB changed nothing measurable.
// The hidden tile (256 x 3072 floats) then lives in L2 and L3, and the GEMM's own row
// blocks (kMc) keep A in cache. Too few rows to give every thread 4 tiles (stage 3 at 224x224:
// 196 rows): one tile per thread holding its whole share, while that share keeps the
// hidden tile in L2 (<= 128 rows) and every thread re-reading the block's weights stays
// cheap (<= 8 MB; stage 4's 19 MB at 49 rows is better split by columns). That case went
// from 28.4 to 26.4 ms per 224x224 forward (2 threads, median of 6 alternating nnrun
// runs). Every path computes each element identically (same kernels, same K order).
std::size_t fused_mlp_rows(std::size_t m, int c, int threads) {
  const double weight_bytes = 8.0 * c * c * sizeof(float);
  const std::size_t want = static_cast<std::size_t>(4 * threads);
  if (weight_bytes > kMlpCachedWeightBytes && (m + kMlpWideTile - 1) / kMlpWideTile >= want)
    return kMlpWideTile;
  if ((m + kMlpTile - 1) / kMlpTile >= want) return kMlpTile;
  const std::size_t share = ((m + threads - 1) / threads + 7) / 8 * 8;
  return threads > 1 && share <= 128 && weight_bytes <= kMlpCachedWeightBytes ? share : 0;
}

// Folds y = W (gamma * z + beta) + b, z the normalised input, into y = W' z + b':
// W'[o][i] = W[o][i] * gamma[i / group], b'[o] = b[o] + sum_i W[o][i] beta[i / group],
// for W [n x k] whose input index i covers `group` consecutive elements per channel
// (1 for a Linear layer, kh * kw for a conv's [cout, cin, kh, kw]). In double.
void fold_affine_in(std::vector<float>& w, std::vector<float>& b, int n, int k, int group,
                    const std::vector<float>& gamma, const std::vector<float>& beta) {
  for (int o = 0; o < n; ++o) {
    float* wo = w.data() + static_cast<std::size_t>(o) * k;
    double acc = b[o];
    for (int i = 0; i < k; ++i) {
      acc += static_cast<double>(wo[i]) * beta[i / group];
      wo[i] = static_cast<float>(static_cast<double>(wo[i]) * gamma[i / group]);
    }
    b[o] = static_cast<float>(acc);
  }
}

// Folds a per-output scale s into y = s * (W x + b): W'[o][i] = s[o] W[o][i], b' = s * b.
void fold_scale_out(std::vector<float>& w, std::vector<float>& b, int n, int k,
                    const std::vector<float>& s) {
  for (int o = 0; o < n; ++o) {
    float* wo = w.data() + static_cast<std::size_t>(o) * k;
    for (int i = 0; i < k; ++i) wo[i] = static_cast<float>(static_cast<double>(wo[i]) * s[o]);
    b[o] = static_cast<float>(static_cast<double>(b[o]) * s[o]);
  }
}

AlignedBuffer to_buffer(const std::vector<float>& v) {
  AlignedBuffer b(v.size());
  std::copy(v.begin(), v.end(), b.data());
  return b;
}

}  // namespace

std::string ConvNeXtConfig::describe() const {
  return "dims " + join(dims) + ", depths " + join(depths);
}

ConvNeXtConfig convnext_tiny_config() { return {{96, 192, 384, 768}, {3, 3, 9, 3}}; }
ConvNeXtConfig convnext_small_config() { return {{96, 192, 384, 768}, {3, 3, 27, 3}}; }
ConvNeXtConfig convnext_base_config() { return {{128, 256, 512, 1024}, {3, 3, 27, 3}}; }

ConvNeXtConfig convnext_config_from(const weights::SafeTensors& st, const std::string& prefix) {
  ConvNeXtConfig cfg;
  const std::string stem = prefix + "0.0.weight";
  if (!st.has(stem))
    throw weights::Error(st.source() + ": missing tensor '" + stem +
                         "' (no ConvNeXt stem under '" + prefix + "')");
  for (int s = 0;; ++s) {
    const std::string stage = prefix + std::to_string(2 * s + 1) + ".";
    int depth = 0;
    while (st.has(stage + std::to_string(depth) + ".layer_scale")) ++depth;
    if (depth == 0) break;
    const auto& shape = st.info(stage + "0.layer_scale").shape;
    if (shape.empty() || shape[0] <= 0 || shape[0] > 65536)
      throw weights::Error(st.source() + ": tensor '" + stage + "0.layer_scale' has an invalid shape");
    cfg.dims.push_back(static_cast<int>(shape[0]));
    cfg.depths.push_back(depth);
  }
  if (cfg.dims.empty())
    throw weights::Error(st.source() + ": missing tensor '" + prefix +
                         "1.0.layer_scale' (no ConvNeXt block found)");
  return cfg;
}

std::vector<weights::TensorSpec> convnext_tensor_specs(const ConvNeXtConfig& cfg,
                                                       const std::string& prefix) {
  using Dims = std::vector<std::int64_t>;
  std::vector<weights::TensorSpec> specs;
  const std::int64_t c0 = cfg.dims[0];
  specs.push_back({prefix + "0.0.weight", Dims{c0, 3, 4, 4}});
  specs.push_back({prefix + "0.0.bias", Dims{c0}});
  specs.push_back({prefix + "0.1.weight", Dims{c0}});
  specs.push_back({prefix + "0.1.bias", Dims{c0}});
  for (std::size_t s = 0; s < cfg.dims.size(); ++s) {
    const std::int64_t c = cfg.dims[s];
    if (s > 0) {
      const std::string d = prefix + std::to_string(2 * s) + ".";
      const std::int64_t ci = cfg.dims[s - 1];
      specs.push_back({d + "0.weight", Dims{ci}});
      specs.push_back({d + "0.bias", Dims{ci}});
      specs.push_back({d + "1.weight", Dims{c, ci, 2, 2}});
      specs.push_back({d + "1.bias", Dims{c}});
    }
    for (int i = 0; i < cfg.depths[s]; ++i) {
      const std::string b = prefix + std::to_string(2 * s + 1) + "." + std::to_string(i) + ".";
      specs.push_back({b + "layer_scale", Dims{c, 1, 1}});
      specs.push_back({b + "block.0.weight", Dims{c, 1, 7, 7}});
      specs.push_back({b + "block.0.bias", Dims{c}});
      specs.push_back({b + "block.2.weight", Dims{c}});
      specs.push_back({b + "block.2.bias", Dims{c}});
      specs.push_back({b + "block.3.weight", Dims{4 * c, c}});
      specs.push_back({b + "block.3.bias", Dims{4 * c}});
      specs.push_back({b + "block.5.weight", Dims{c, 4 * c}});
      specs.push_back({b + "block.5.bias", Dims{c}});
    }
  }
  return specs;
}

ConvNeXt::ConvNeXt(const weights::SafeTensors& st, const std::string& prefix,
                   Precision precision)
    : cfg_(convnext_config_from(st, prefix)), precision_(precision) {
  if (precision_ == Precision::Bf16 && !bf16_gemm_available())
    throw Error("convnext: precision bf16 needs AVX512_BF16, which this CPU (or the kernel cap) does not offer");
  weights::check_tensors(st, convnext_tensor_specs(cfg_, prefix));
  auto count = [this](std::size_t floats) { weight_bytes_ += floats * sizeof(float); };

  {
    auto w = st.f32(prefix + "0.0.weight");  // [c0, 3, 4, 4] = [c0 x 48], K order (c, ky, kx)
    stem_w_ = GemmWeights::pack(w.data(), cfg_.dims[0], 48);
    stem_b_ = load_vec(st, prefix + "0.0.bias");
    weight_bytes_ += stem_w_.bytes();
    count(cfg_.dims[0]);
  }
  // Dump and profile names: the weights' prefix ("features.") is torchvision's module path.
  name_ = prefix.empty() ? "features" : prefix.substr(0, prefix.size() - (prefix.back() == '.' ? 1 : 0));
  stem_name_ = prefix + "0";
  stem_covers_ = module_list(prefix + "0.", {"0", "1"});
  stem_gamma_ = load_vec(st, prefix + "0.1.weight");
  stem_beta_ = load_vec(st, prefix + "0.1.bias");
  count(2 * cfg_.dims[0]);

  for (std::size_t s = 0; s < cfg_.dims.size(); ++s) {
    Stage stage;
    stage.dim = cfg_.dims[s];
    stage.name = prefix + std::to_string(2 * s + 1);
    const int c = stage.dim;
    if (s > 0) {
      const std::string d = prefix + std::to_string(2 * s) + ".";
      stage.has_down = true;
      stage.down_name = prefix + std::to_string(2 * s);
      stage.down_covers = module_list(stage.down_name + ".", {"0", "1"});
      Conv2dParams p;
      p.cin = cfg_.dims[s - 1];
      p.cout = c;
      p.kh = p.kw = p.stride_h = p.stride_w = 2;
      auto w = st.f32(d + "1.weight");
      auto b = st.f32(d + "1.bias");
      // Unpadded 2x2/2: every tap reads a normalised pixel, so beta folds exactly.
      fold_affine_in(w, b, c, p.cin * 4, 4, st.f32(d + "0.weight"), st.f32(d + "0.bias"));
      stage.down = Conv2dWeights::pack(w.data(), b.data(), p);
      weight_bytes_ += stage.down.gemm().bytes();
      count(c);  // bias (LayerNorm folded into the weights)
    }
    for (int i = 0; i < cfg_.depths[s]; ++i) {
      const std::string b = prefix + std::to_string(2 * s + 1) + "." + std::to_string(i) + ".";
      Block blk;
      blk.name = b.substr(0, b.size() - 1);
      blk.dw_name = b + "block.0";
      // LayerNorm (affine folded into pw1), pw1, GELU, pw2, the layer scale (folded into
      // pw2) and the residual run as one fused tile: the block output stands for them all.
      blk.covers = module_list(b, {"block", "block.5", "block.6", "stochastic_depth"});
      blk.perm_name = b + "block.1";
      blk.ln_name = b + "block.2";
      blk.pw1_name = b + "block.3";
      blk.gelu_name = b + "block.4";
      blk.ln_gamma = load_vec(st, b + "block.2.weight");
      blk.ln_beta = load_vec(st, b + "block.2.bias");
      if (precision_ == Precision::Bf16)  // no unfused dump layers in bf16: the tile covers them
        blk.covers = module_list(b, {"block", "block.1", "block.2", "block.3", "block.4", "block.5", "block.6",
                                     "stochastic_depth"});
      DwConvParams dp;  // 7x7, stride 1, pad 3
      auto dw = st.f32(b + "block.0.weight");
      auto dwb = st.f32(b + "block.0.bias");
      blk.dw = DwConvWeights::pack(dw.data(), dwb.data(), c, dp);
      auto w1 = st.f32(b + "block.3.weight");
      auto b1 = st.f32(b + "block.3.bias");
      fold_affine_in(w1, b1, 4 * c, c, 1, st.f32(b + "block.2.weight"), st.f32(b + "block.2.bias"));
      blk.b1 = to_buffer(b1);
      auto w2 = st.f32(b + "block.5.weight");
      auto b2 = st.f32(b + "block.5.bias");
      fold_scale_out(w2, b2, c, 4 * c, st.f32(b + "layer_scale"));
      blk.b2 = to_buffer(b2);
      if (precision_ == Precision::Bf16) {
        // Folded in float first, so bf16 rounds the same weights the float path uses.
        blk.pw1_bf16 = GemmWeightsBf16::pack(w1.data(), 4 * c, c);
        blk.pw2_bf16 = GemmWeightsBf16::pack(w2.data(), c, 4 * c);
        weight_bytes_ += blk.pw1_bf16.bytes() + blk.pw2_bf16.bytes();
      } else {
        blk.pw1 = GemmWeights::pack(w1.data(), 4 * c, c);
        blk.pw2 = GemmWeights::pack(w2.data(), c, 4 * c);
        weight_bytes_ += blk.pw1.bytes() + blk.pw2.bytes();
      }
      count(49 * c + c + 4 * c + c + 2 * c);  // dw, dw bias, b1, b2, LayerNorm affine (dumps)
      stage.blocks.push_back(std::move(blk));
    }
    stages_.push_back(std::move(stage));
  }
}

void ConvNeXt::plan(int n, int h, int w) {
  if (n < 1) throw Error("convnext: batch size must be at least 1");
  if (h < 32 || w < 32)
    throw Error("convnext: input " + std::to_string(h) + "x" + std::to_string(w) +
                " is smaller than the minimum 32x32");
  planned_threads_ = num_threads();
  in_shape_ = {n, h, w, 3};
  stage_shapes_.clear();
  prof_.clear();

  Shape s{n, h / 4, w / 4, cfg_.dims[0]};
  std::size_t act = s.count();
  // Chunks of output rows with at least kMlpTile pixels feed the GEMMs enough rows.
  stem_chunk_ = std::min(s.h, (kMlpTile + s.w - 1) / s.w);
  conv_scratch_ = static_cast<std::size_t>(stem_chunk_) * s.w * 48;
  std::size_t mlp_scratch = 0;  // per thread for fused stages; whole for unfused
  std::size_t shared_scratch = 0;
  // Bytes moved (Profiler): inputs, weights and outputs once each, 4 bytes a float.
  prof_stem_ = prof_.add(stem_name_, "conv 4x4/4 + LayerNorm", nchw_str(s), 2.0 * s.count() * 48,
                         4.0 * (3.0 * n * h * w + 51.0 * s.c + s.count()));
  for (std::size_t si = 0; si < stages_.size(); ++si) {
    Stage& st = stages_[si];
    if (st.has_down) {
      Shape d = conv2d_output_shape(s, st.down.params());
      if (d.h < 1 || d.w < 1) throw Error("convnext: input too small for the downsampling layers");
      const std::size_t dm = static_cast<std::size_t>(d.n) * d.h * d.w;
      const std::size_t patch = 4 * static_cast<std::size_t>(s.c);
      st.down_whole = dm < static_cast<std::size_t>(128 * planned_threads_) && planned_threads_ > 1;
      st.down_chunk = std::min(d.h, (kMlpTile + d.w - 1) / d.w);
      if (st.down_whole)
        shared_scratch = std::max(shared_scratch, dm * patch);
      else
        conv_scratch_ = std::max(conv_scratch_, st.down_chunk * d.w * patch);
      st.prof_down = prof_.add(st.down_name, "LayerNorm + conv 2x2/2", nchw_str(d), 2.0 * d.count() * 4 * s.c,
                               4.0 * (s.count() + 4.0 * s.c * d.c + d.c + d.count()));
      s = d;
    }
    stage_shapes_.push_back(s);
    act = std::max(act, s.count());
    const std::size_t m = static_cast<std::size_t>(s.n) * s.h * s.w;
    const std::size_t c = st.dim;
    st.mlp_tile = fused_mlp_rows(m, st.dim, planned_threads_);
    st.band = 0;
    if (const std::size_t rows = st.mlp_tile) {
      std::size_t per_thread = mlp_scratch_floats(rows, st.dim);
      if (static_cast<long long>(s.n) * s.h >= 2LL * kDwMlpBand * planned_threads_) {
        st.band = kDwMlpBand;
        per_thread += static_cast<std::size_t>(st.band) * s.w * c;
      }
      mlp_scratch = std::max(mlp_scratch, per_thread);
    } else {
      shared_scratch = std::max(shared_scratch, mlp_scratch_floats(m, st.dim));
    }
    for (std::size_t i = 0; i < st.blocks.size(); ++i) {
      Block& b = st.blocks[i];
      b.prof_dw = prof_.add(b.dw_name, "dwconv 7x7", nchw_str(s), 2.0 * s.count() * 49,
                            4.0 * (2.0 * s.count() + 50.0 * c));
      // The hidden [rows, 4C] tile stays in cache: input, residual, weights, output.
      b.prof_mlp = prof_.add(b.name, "LN+pw1+GELU+pw2+scale+res", nchw_str(s), 2.0 * m * c * 4 * c * 2,
                             4.0 * (3.0 * s.count() + 8.0 * c * c + 5.0 * c));
    }
  }
  out_shape_ = s;
  scratch_per_thread_ = round_up_floats(std::max(conv_scratch_, mlp_scratch));  // 64-byte aligned shares
  act_a_.resize(act);
  act_b_.resize(act);
  band_dw_ms_.assign(static_cast<std::size_t>(std::max(planned_threads_, 1)), 0.0);
  scratch_.resize(std::max(scratch_per_thread_ * planned_threads_, shared_scratch));
}

std::size_t ConvNeXt::arena_bytes() const {
  return (act_a_.size() + act_b_.size() + scratch_.size()) * sizeof(float);
}

double ConvNeXt::flops() const {
  double f = 0;
  for (const auto& e : prof_.entries()) f += e.flops;
  return f;
}

// Stem: per chunk of output rows, the 4x4 patches straight from the NCHW input
// (K order c, ky, kx), the GEMM with bias, then LayerNorm on the rows while in cache.
void ConvNeXt::run_stem(const float* input_nchw, Shape s) {
  Profiler::Scope t(&prof_, prof_stem_);
  const int ih = in_shape_.h, iw = in_shape_.w, ow = s.w, c0 = s.c;
  const std::size_t plane = static_cast<std::size_t>(ih) * iw;
  const int per_image = (s.h + stem_chunk_ - 1) / stem_chunk_;
  const int chunks = s.n * per_image;
  GemmEpilogue ep;
  ep.bias = stem_b_.data();
  parallel_for(chunks, true, [&](long long ci_) {
    const int ci = static_cast<int>(ci_);
    float* col = scratch_.data() + scratch_per_thread_ * thread_index();
    const int n = ci / per_image, y0 = ci % per_image * stem_chunk_;
    const int y1 = std::min(s.h, y0 + stem_chunk_);
    const float* img = input_nchw + static_cast<std::size_t>(n) * 3 * plane;
    float* p = col;
    for (int oy = y0; oy < y1; ++oy)
      for (int ox = 0; ox < ow; ++ox)
        for (int c = 0; c < 3; ++c)
          for (int ky = 0; ky < 4; ++ky, p += 4)
            std::memcpy(p, img + c * plane + static_cast<std::size_t>(4 * oy + ky) * iw + 4 * ox,
                        4 * sizeof(float));
    const int rows = (y1 - y0) * ow;
    float* out = act_a_.data() + ((static_cast<std::size_t>(n) * s.h + y0) * ow) * c0;
    gemm(rows, col, 48, stem_w_, out, c0, ep);
    layernorm(rows, c0, out, c0, out, c0, stem_gamma_.data(), stem_beta_.data(), cfg_.eps, stem_w_.isa());
  });
}

// Downsampling: LayerNorm (gamma/beta folded into the conv) written straight into the
// 2x2/2 im2col rows (K order ky, kx, c; each input pixel is normalised once), then the
// GEMM. Large maps go in chunks of output rows per thread; small ones are one im2col
// and a GEMM split over columns (at 224x224 the 7x7 map was 7 GEMMs of 7 rows, each
// streaming all of W).
void ConvNeXt::run_down(const Stage& st, Shape prev, Shape s) {
  Profiler::Scope t(&prof_, st.prof_down);
  const int cin = prev.c, ow = s.w;
  const std::ptrdiff_t patch = 4 * static_cast<std::ptrdiff_t>(cin);
  const float* x = act_a_.data();
  auto im2col = [&](int n, int oy, float* dst) {
    for (int ky = 0; ky < 2; ++ky) {
      const float* src = x + ((static_cast<std::size_t>(n) * prev.h + 2 * oy + ky) * prev.w) * cin;
      float* d = dst + ky * 2 * cin;
      layernorm(ow, cin, src, 2 * cin, d, patch, nullptr, nullptr, cfg_.eps, stem_w_.isa());
      layernorm(ow, cin, src + cin, 2 * cin, d + cin, patch, nullptr, nullptr, cfg_.eps, stem_w_.isa());
    }
  };
  GemmEpilogue ep;
  ep.bias = st.down.bias();
  if (st.down_whole) {
    const int rows = s.n * s.h;
    parallel_for(rows, true, [&](long long r_) {
      const int r = static_cast<int>(r_);
      im2col(r / s.h, r % s.h, scratch_.data() + static_cast<std::size_t>(r) * ow * patch);
    });
    gemm_parallel(rows * ow, scratch_.data(), patch, st.down.gemm(), act_b_.data(), s.c, ep);
    return;
  }
  const int per_image = (s.h + st.down_chunk - 1) / st.down_chunk;
  const int chunks = s.n * per_image;
  parallel_for(chunks, true, [&](long long ci_) {
    const int ci = static_cast<int>(ci_);
    float* col = scratch_.data() + scratch_per_thread_ * thread_index();
    const int n = ci / per_image, y0 = ci % per_image * st.down_chunk;
    const int y1 = std::min(s.h, y0 + st.down_chunk);
    for (int oy = y0; oy < y1; ++oy)
      im2col(n, oy, col + static_cast<std::size_t>(oy - y0) * ow * patch);
    float* out = act_b_.data() + ((static_cast<std::size_t>(n) * s.h + y0) * ow) * s.c;
    gemm((y1 - y0) * ow, col, patch, st.down.gemm(), out, s.c, ep);
  });
}

namespace {

// bf16 row stride for c channels: K pairs must be complete.
std::size_t bf16_stride(int c) { return static_cast<std::size_t>(c) + (c & 1); }

// Rows of a float matrix to bf16, split over the team by rows (the bits do not depend on
// the split).
void convert_rows_parallel(std::size_t rows, int cols, const float* src, bf16* dst,
                           std::size_t ldd) {
  const std::size_t chunk = 16;
  const std::ptrdiff_t chunks = static_cast<std::ptrdiff_t>((rows + chunk - 1) / chunk);
  parallel_for(chunks, true, [&](long long i_) {
    const std::ptrdiff_t i = static_cast<std::ptrdiff_t>(i_);
    const std::size_t r0 = static_cast<std::size_t>(i) * chunk, r1 = std::min(rows, r0 + chunk);
    convert_to_bf16(static_cast<int>(r1 - r0), cols, src + r0 * cols, cols, dst + r0 * ldd,
                    static_cast<std::ptrdiff_t>(ldd));
  });
}

}  // namespace

std::size_t ConvNeXt::mlp_scratch_floats(std::size_t rows, int c) const {
  std::size_t floats = round_up_floats(rows * c) + round_up_floats(rows * 4 * c);
  if (precision_ == Precision::Bf16)
    floats += round_up_floats((rows * bf16_stride(c) + 1) / 2) + round_up_floats(rows * 2 * c);
  return floats;
}

ConvNeXt::MlpScratch ConvNeXt::mlp_scratch(float* base, std::size_t rows, int c) const {
  MlpScratch s{};
  s.ln = base;
  s.hid = s.ln + round_up_floats(rows * c);
  if (precision_ == Precision::Bf16) {
    float* lnh = s.hid + round_up_floats(rows * 4 * c);
    s.ln_bf16 = reinterpret_cast<bf16*>(lnh);
    s.hid_bf16 = reinterpret_cast<bf16*>(lnh + round_up_floats((rows * bf16_stride(c) + 1) / 2));
  }
  return s;
}

void ConvNeXt::run_mlp_rows(const Block& b, int c, int rows, const float* t, const float* res,
                            float* y, const MlpScratch& sc) {
  layernorm(rows, c, t, c, sc.ln, c, nullptr, nullptr, cfg_.eps, stem_w_.isa());
  GemmEpilogue e1;
  e1.bias = b.b1.data();
  e1.act = Act::Gelu;
  GemmEpilogue e2;
  e2.bias = b.b2.data();
  e2.residual = res;
  e2.ldr = c;
  if (precision_ == Precision::Bf16) {
    const std::ptrdiff_t ldl = static_cast<std::ptrdiff_t>(bf16_stride(c));
    convert_to_bf16(rows, c, sc.ln, c, sc.ln_bf16, ldl);
    gemm_bf16(rows, sc.ln_bf16, ldl, b.pw1_bf16, sc.hid, 4 * c, e1);
    convert_to_bf16(rows, 4 * c, sc.hid, 4 * c, sc.hid_bf16, 4 * c);
    gemm_bf16(rows, sc.hid_bf16, 4 * c, b.pw2_bf16, y, c, e2);
    return;
  }
  gemm(rows, sc.ln, c, b.pw1, sc.hid, 4 * c, e1);
  gemm(rows, sc.hid, 4 * c, b.pw2, y, c, e2);
}

// One block with the depthwise and the MLP fused per band of image rows: each id of the
// team takes an equal contiguous share of the n * h image rows and, band by band, writes
// the depthwise output of the band into its scratch and runs the MLP tiles on it while it
// is in cache, the result going to act_b_ (the depthwise still reads the block input
// around the band), which then becomes act_a_. The depthwise output never travels to
// memory and back. Every element is computed as on the unbanded path.
// Upward: the bands go from the end of the share to its start. The forward alternates
// (upward after the stem or a downsampling layer, then down, up, ...), so each block starts on
// the rows the previous one wrote last, which are still in L2/L3 (a stage-1 activation
// at 1280x1920 is 59 MB, larger than the L3). Medians of 11 alternating nnrun runs at
// 1280x1920 on Zen 5, 2 threads: about 1 % less time per forward, lower in 9 of 11 pairs.
// Profiling: the depthwise row gets the slowest thread's summed depthwise time, the MLP
// row the rest of the block's wall time.
void ConvNeXt::run_block_banded(const Stage& st, const Block& b, Shape s, bool upward) {
  using Clock = std::chrono::steady_clock;
  const bool timed = prof_.enabled();
  const Clock::time_point start = timed ? Clock::now() : Clock::time_point();
  const int c = s.c;
  const std::size_t tile = st.mlp_tile;
  const ConstTensorView in(act_a_.data(), s);
  const int team_n = team_size();
  parallel_team(team_n, [&](int id, int team) {
    const long long rows = static_cast<long long>(s.n) * s.h;
    const long long r0 = rows * id / team, r1 = rows * (id + 1) / team;
    float* base = scratch_.data() + scratch_per_thread_ * id;
    const MlpScratch sc = mlp_scratch(base, tile, c);
    float* band = base + mlp_scratch_floats(tile, c);
    double dw_ms = 0;
    for (long long done = 0; done < r1 - r0;) {
      // The next band, rows [y0, y1) of image n: the share's rows taken from r0 downward,
      // or from r1 - 1 upward.
      int n, y0, y1;
      if (upward) {
        const long long last = r1 - 1 - done;
        n = static_cast<int>(last / s.h);
        y1 = static_cast<int>(last % s.h) + 1;
        y0 = static_cast<int>(std::max<long long>({0, y1 - st.band, y1 - (r1 - r0 - done)}));
      } else {
        const long long r = r0 + done;
        n = static_cast<int>(r / s.h);
        y0 = static_cast<int>(r % s.h);
        y1 = static_cast<int>(std::min<long long>({s.h, y0 + st.band, y0 + (r1 - r)}));
      }
      const Clock::time_point t0 = timed ? Clock::now() : Clock::time_point();
      dwconv_rows(in, b.dw, n, y0, y1, band);
      if (timed) dw_ms += std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
      const std::size_t m0 = (static_cast<std::size_t>(n) * s.h + y0) * s.w;
      const std::size_t pixels = static_cast<std::size_t>(y1 - y0) * s.w;
      for (std::size_t p = 0; p < pixels; p += tile) {
        const std::size_t off = (m0 + p) * c;
        run_mlp_rows(b, c, static_cast<int>(std::min(tile, pixels - p)), band + p * c,
                     act_a_.data() + off, act_b_.data() + off, sc);
      }
      done += y1 - y0;
    }
    if (timed) band_dw_ms_[id] = dw_ms;
  });
  std::swap(act_a_, act_b_);
  if (timed) {
    const double total = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    const double dw = *std::max_element(band_dw_ms_.begin(), band_dw_ms_.begin() + team_n);
    prof_.record(b.prof_dw, dw);
    prof_.record(b.prof_mlp, total - dw);
  }
}

void ConvNeXt::run_block(const Stage& st, const Block& b, Shape s, bool upward) {
  if (st.band > 0 && !dump_) return run_block_banded(st, b, s, upward);
  const int c = s.c;
  {
    Profiler::Scope t(&prof_, b.prof_dw);
    dwconv(ConstTensorView(act_a_.data(), s), b.dw, TensorView{act_b_.data(), s});
  }
  if (dump_) {
    dump_nhwc(dump_, b.dw_name, ConstTensorView(act_b_.data(), s));
    if (precision_ == Precision::F32) dump_mlp_layers(b, s);
  }
  Profiler::Scope t(&prof_, b.prof_mlp);
  const std::size_t m = static_cast<std::size_t>(s.n) * s.h * s.w;
  if (const std::size_t tile = st.mlp_tile) {
    // Each id of the team takes an equal contiguous share of 8-row groups (whole tiles
    // would leave one id a tile more: 7 against 6 at 28x28) and runs it in tiles of
    // `tile` rows. A row's result does not depend on its tile. (Finer dynamic tiles were
    // measured slower, quiet and loaded: the pool already balances the ids.)
    parallel_team(team_size(), [&](int id, int team) {
      const std::size_t groups = (m + 7) / 8;
      const std::size_t r0 = std::min(m, groups * id / team * 8);
      const std::size_t r1 = std::min(m, groups * (id + 1) / team * 8);
      const MlpScratch sc = mlp_scratch(scratch_.data() + scratch_per_thread_ * id, tile, c);
      for (std::size_t m0 = r0; m0 < r1; m0 += tile) {
        float* x = act_a_.data() + m0 * c;
        run_mlp_rows(b, c, static_cast<int>(std::min(r1, m0 + tile) - m0), act_b_.data() + m0 * c, x, x, sc);
      }
    });
    return;
  }
  const MlpScratch sc = mlp_scratch(scratch_.data(), m, c);
  layernorm_parallel(m, c, act_b_.data(), c, sc.ln, c, nullptr, nullptr, cfg_.eps);
  GemmEpilogue e1;
  e1.bias = b.b1.data();
  e1.act = Act::Gelu;
  GemmEpilogue e2;
  e2.bias = b.b2.data();
  e2.residual = act_a_.data();
  e2.ldr = c;
  const int rows = static_cast<int>(m);
  if (precision_ == Precision::Bf16) {
    const std::size_t ldl = bf16_stride(c);
    convert_rows_parallel(m, c, sc.ln, sc.ln_bf16, ldl);
    gemm_bf16_parallel(rows, sc.ln_bf16, static_cast<std::ptrdiff_t>(ldl), b.pw1_bf16, sc.hid, 4 * c, e1);
    convert_rows_parallel(m, 4 * c, sc.hid, sc.hid_bf16, 4 * static_cast<std::size_t>(c));
    gemm_bf16_parallel(rows, sc.hid_bf16, 4 * c, b.pw2_bf16, act_a_.data(), c, e2);
    return;
  }
  gemm_parallel(rows, sc.ln, c, b.pw1, sc.hid, 4 * c, e1);
  gemm_parallel(rows, sc.hid, 4 * c, b.pw2, act_a_.data(), c, e2);
}

std::string ConvNeXt::dump_path_of(Precision precision) {
  if (precision == Precision::Bf16)
    return "fused (bf16: each ConvNeXt block output covers its whole MLP, block.1 to block.6)";
  return "fused, plus for the dump each ConvNeXt block's block.1 to block.4 (permute, LayerNorm with its own "
         "affine, Linear, GELU) computed layer by layer from the depthwise output beside the fused tile, which "
         "computes the block output (block.5, block.6, layer scale and residual)";
}

// The MLP's first layers for the dump, as the layer-by-layer path computes them (the
// same kernels as the fused tile, so block.4 is bitwise the tile's hidden rows).
void ConvNeXt::dump_mlp_layers(const Block& b, Shape s) {
  if (!dump_->wants(b.perm_name) && !dump_->wants(b.ln_name) && !dump_->wants(b.pw1_name) &&
      !dump_->wants(b.gelu_name))
    return;
  const int c = s.c;
  const std::size_t m = static_cast<std::size_t>(s.n) * s.h * s.w;
  float* ln = dump_->scratch(m * c * 6);  // normalised, affine, hidden
  float* affine = ln + m * c;
  float* hid = affine + m * c;
  const float* dw = act_b_.data();
  dump_nhwc_as_nhwc(dump_, b.perm_name, ConstTensorView(dw, s));
  layernorm_parallel(m, c, dw, c, ln, c, nullptr, nullptr, cfg_.eps);
  layernorm_parallel(m, c, dw, c, affine, c, b.ln_gamma.data(), b.ln_beta.data(), cfg_.eps);
  dump_nhwc_as_nhwc(dump_, b.ln_name, ConstTensorView(affine, s));
  const Shape hs{s.n, s.h, s.w, 4 * c};
  const int rows = static_cast<int>(m);
  GemmEpilogue e1;
  e1.bias = b.b1.data();
  gemm_parallel(rows, ln, c, b.pw1, hid, 4 * c, e1);
  dump_nhwc_as_nhwc(dump_, b.pw1_name, ConstTensorView(hid, hs));
  e1.act = Act::Gelu;
  gemm_parallel(rows, ln, c, b.pw1, hid, 4 * c, e1);
  dump_nhwc_as_nhwc(dump_, b.gelu_name, ConstTensorView(hid, hs));
}

ConstTensorView ConvNeXt::forward(const float* input_nchw) {
  if (act_a_.empty()) throw Error("convnext: forward() before plan()");
  if (num_threads() > planned_threads_)
    throw Error("convnext: the thread count rose to " + std::to_string(num_threads()) +
                " after plan() was made for " + std::to_string(planned_threads_) +
                "; call plan() again");
  run_stem(input_nchw, stage_shapes_[0]);
  if (dump_) dump_nhwc(dump_, stem_name_, ConstTensorView(act_a_.data(), stage_shapes_[0]), stem_covers_);
  // act_a_ holds the residual stream, act_b_ the depthwise output (a banded block: the
  // block output, and the two swap roles); a downsampling layer normalises act_a_ in
  // place, convolves into act_b_ and the two swap roles.
  Shape s = stage_shapes_[0];
  for (std::size_t si = 0; si < stages_.size(); ++si) {
    const Stage& st = stages_[si];
    if (st.has_down) {
      const Shape prev = s;
      s = stage_shapes_[si];
      run_down(st, prev, s);
      std::swap(act_a_, act_b_);
      if (dump_) dump_nhwc(dump_, st.down_name, ConstTensorView(act_a_.data(), s), st.down_covers);
    }
    for (std::size_t bi = 0; bi < st.blocks.size(); ++bi) {
      const Block& b = st.blocks[bi];
      run_block(st, b, s, bi % 2 == 0);
      if (dump_) dump_nhwc(dump_, b.name, ConstTensorView(act_a_.data(), s), b.covers);
    }
    if (dump_) dump_nhwc(dump_, st.name, ConstTensorView(act_a_.data(), s));
  }
  if (dump_) dump_nhwc(dump_, name_, ConstTensorView(act_a_.data(), out_shape_));
  return ConstTensorView(act_a_.data(), out_shape_);
}

}  // namespace nn
