#include "nn/models/detection/layers.h"

#include <algorithm>
#include <cmath>

#include "nn/threads.h"

namespace nn::detection {

namespace {

// Per-channel scale and shift of a frozen batch norm, in float as FrozenBatchNorm2d.
void bn_scale_shift(const weights::SafeTensors& st, const std::string& bn, float eps, std::vector<float>* scale,
                    std::vector<float>* shift) {
  const auto g = st.f32(bn + "weight"), b = st.f32(bn + "bias"), m = st.f32(bn + "running_mean"),
             v = st.f32(bn + "running_var");
  scale->resize(g.size());
  shift->resize(g.size());
  for (std::size_t c = 0; c < g.size(); ++c) {
    (*scale)[c] = g[c] * (1.0f / std::sqrt(v[c] + eps));
    (*shift)[c] = b[c] - m[c] * (*scale)[c];
  }
}

std::vector<float> folded(const weights::SafeTensors& st, const std::string& conv_weight, const std::vector<float>& scale) {
  std::vector<float> w = st.f32(conv_weight);
  const std::size_t per = w.size() / scale.size();
  for (std::size_t o = 0; o < scale.size(); ++o)
    for (std::size_t i = 0; i < per; ++i) w[o * per + i] *= scale[o];
  return w;
}

}  // namespace

void add_conv_bn_specs(std::vector<weights::TensorSpec>& specs, const std::string& conv_weight,
                       const std::string& bn, const Dims& shape) {
  specs.push_back({conv_weight, shape});
  for (const char* leaf : {"weight", "bias", "running_mean", "running_var"}) specs.push_back({bn + leaf, {shape[0]}});
}

Conv2dWeights load_conv_bn(const weights::SafeTensors& st, const std::string& conv_weight, const std::string& bn,
                           const Conv2dParams& p, float eps) {
  std::vector<float> scale, shift;
  bn_scale_shift(st, bn, eps, &scale, &shift);
  const std::vector<float> w = folded(st, conv_weight, scale);
  return Conv2dWeights::pack(w.data(), shift.data(), p);
}

DwConvWeights load_dwconv_bn(const weights::SafeTensors& st, const std::string& conv_weight, const std::string& bn,
                             int channels, const DwConvParams& p, float eps) {
  std::vector<float> scale, shift;
  bn_scale_shift(st, bn, eps, &scale, &shift);
  const std::vector<float> w = folded(st, conv_weight, scale);
  return DwConvWeights::pack(w.data(), shift.data(), channels, p);
}

Conv2dWeights load_conv(const weights::SafeTensors& st, const std::string& prefix, const Conv2dParams& p) {
  const auto w = st.f32(prefix + "weight"), b = st.f32(prefix + "bias");
  return Conv2dWeights::pack(w.data(), b.data(), p);
}

int add_conv_row(Profiler* prof, const std::string& layer, const Conv2dWeights& w, const Shape& out) {
  if (!prof) return -1;
  const Conv2dParams& p = w.params();
  std::string op = "conv " + std::to_string(p.kh) + "x" + std::to_string(p.kw);
  if (p.stride_h > 1) op += "/" + std::to_string(p.stride_h);
  if (w.is_winograd()) op += " winograd";
  // Bytes moved: the input (about out * stride^2 pixels), weights and output once each.
  const double in = static_cast<double>(out.n) * out.h * p.stride_h * out.w * p.stride_w * p.cin;
  const double weights = static_cast<double>(p.cout) * p.cin * p.kh * p.kw / std::max(p.groups, 1) + p.cout;
  return prof->add(layer, op, nchw_str(out), 2.0 * out.count() * p.cin * p.kh * p.kw,
                   4.0 * (in + weights + static_cast<double>(out.count())));
}

void conv2d_timed(Profiler* prof, int row, const ConstTensorView& in, const Conv2dWeights& w, const TensorView& out,
                  float* scratch, Act act, const float* residual, bool act_after_residual) {
  Profiler::Scope t(prof, row);
  conv2d(in, w, out, scratch, act, residual, act_after_residual);
}

void ConvScratch::require(const Conv2dWeights& w, int out_w) {
  per_thread_ = std::max(per_thread_, conv2d_scratch_floats(w, out_w));
}

void ConvScratch::allocate() {
  threads_ = std::max(1, num_threads());
  buf_.resize(per_thread_ * threads_ + 16);
}

float* ConvScratch::get() {
  if (num_threads() > threads_) allocate();
  return buf_.data();
}

}  // namespace nn::detection
