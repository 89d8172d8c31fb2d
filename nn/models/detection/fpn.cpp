#include "nn/models/detection/fpn.h"

#include <algorithm>

#include "nn/resize.h"

namespace nn::detection {

namespace {

Conv2dParams params(int cin, int k) {
  Conv2dParams p;
  p.cin = cin, p.cout = Fpn::kChannels, p.kh = p.kw = k, p.pad_h = p.pad_w = k / 2;
  return p;
}

// The module of level i's lateral (inner) or output (layer) conv; torchvision's
// Conv2dNormActivation wraps the conv as ".0", whose weights carry the ".0".
std::string inner_module(const std::string& prefix, std::size_t i, WeightLayout layout) {
  return layout == WeightLayout::Detectron2 ? prefix + "fpn_lateral" + std::to_string(i + 2)
                                         : prefix + "inner_blocks." + std::to_string(i);
}
std::string layer_module(const std::string& prefix, std::size_t i, WeightLayout layout) {
  return layout == WeightLayout::Detectron2 ? prefix + "fpn_output" + std::to_string(i + 2)
                                         : prefix + "layer_blocks." + std::to_string(i);
}
std::string conv_of(const std::string& module, WeightLayout layout) {
  return layout == WeightLayout::Detectron2 ? module : module + ".0";
}
std::string inner_name(const std::string& prefix, std::size_t i, WeightLayout layout) {
  return conv_of(inner_module(prefix, i, layout), layout) + ".";
}
std::string layer_name(const std::string& prefix, std::size_t i, WeightLayout layout) {
  return conv_of(layer_module(prefix, i, layout), layout) + ".";
}

}  // namespace

std::vector<weights::TensorSpec> Fpn::tensor_specs(const std::string& prefix, const std::vector<int>& in,
                                                  WeightLayout layout) {
  std::vector<weights::TensorSpec> s;
  for (std::size_t i = 0; i < in.size(); ++i) {
    s.push_back({inner_name(prefix, i, layout) + "weight", {kChannels, in[i], 1, 1}});
    s.push_back({inner_name(prefix, i, layout) + "bias", {kChannels}});
    s.push_back({layer_name(prefix, i, layout) + "weight", {kChannels, kChannels, 3, 3}});
    s.push_back({layer_name(prefix, i, layout) + "bias", {kChannels}});
  }
  return s;
}

Fpn::Fpn(const weights::SafeTensors& st, const std::string& prefix, const std::vector<int>& in, WeightLayout layout) {
  for (std::size_t i = 0; i < in.size(); ++i) {
    inner_.push_back(load_conv(st, inner_name(prefix, i, layout), params(in[i], 1)));
    layer_.push_back(load_conv(st, layer_name(prefix, i, layout), params(kChannels, 3)));
    inner_names_.push_back(inner_module(prefix, i, layout));
    inner_covers_.push_back(conv_of(inner_names_.back(), layout));
    layer_names_.push_back(layer_module(prefix, i, layout));
    layer_covers_.push_back(conv_of(layer_names_.back(), layout));
  }
}

void Fpn::plan(const std::vector<Shape>& inputs) {
  const std::size_t n = inputs.size();
  inner_out_.resize(n);
  upsampled_.resize(n);
  out_.resize(n);
  scratch_ = ConvScratch();
  for (std::size_t i = 0; i < n; ++i) {
    const Shape s{1, inputs[i].h, inputs[i].w, kChannels};
    inner_out_[i].resize(s);
    upsampled_[i].resize(s);
    out_[i].resize(s);
    scratch_.require(inner_[i], s.w);
    scratch_.require(layer_[i], s.w);
  }
  const Shape last = out_[n - 1].shape;
  pool_.resize({1, (last.h - 1) / 2 + 1, (last.w - 1) / 2 + 1, kChannels});
  scratch_.allocate();
  result_.reserve(inputs.size() + 1);
}

void Fpn::dump_level(std::size_t i, bool lateral_is_module) const {
  if (lateral_is_module) dump_nhwc(dump_, inner_names_[i], inner_out_[i].cview(), inner_covers_[i]);
  dump_nhwc(dump_, layer_names_[i], out_[i].cview(), layer_covers_[i]);
}

const std::vector<ConstTensorView>& Fpn::forward(const std::vector<ConstTensorView>& x) {
  const std::size_t n = x.size();
  conv2d(x[n - 1], inner_[n - 1], inner_out_[n - 1].view(), scratch_.get());
  conv2d(inner_out_[n - 1].cview(), layer_[n - 1], out_[n - 1].view(), scratch_.get());
  if (dump_) dump_level(n - 1, true);
  for (std::size_t i = n - 1; i-- > 0;) {
    // last_inner = lateral + interpolate(last_inner, size=lateral size, mode="nearest");
    // the epilogue adds the residual after the bias, i.e. (conv + bias) + top_down.
    upsample_nearest(inner_out_[i + 1].cview(), upsampled_[i].view());
    conv2d(x[i], inner_[i], inner_out_[i].view(), scratch_.get(), Act::None, upsampled_[i].data.data());
    conv2d(inner_out_[i].cview(), layer_[i], out_[i].view(), scratch_.get());
    if (dump_) dump_level(i, false);
  }
  const Shape last = out_[n - 1].shape;
  for (int y = 0; y < pool_.shape.h; ++y)
    for (int xx = 0; xx < pool_.shape.w; ++xx) {
      const float* src = out_[n - 1].cview().pixel(0, 2 * y, 2 * xx);
      std::copy(src, src + last.c, pool_.view().pixel(0, y, xx));
    }
  result_.clear();
  for (auto& o : out_) result_.push_back(o.cview());
  result_.push_back(pool_.cview());
  return result_;
}

}  // namespace nn::detection
