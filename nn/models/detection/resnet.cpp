#include "nn/models/detection/resnet.h"

#include "nn/pool.h"

namespace nn::detection {

namespace {

constexpr int kBlocks[4] = {3, 4, 6, 3};

Conv2dParams conv(int cin, int cout, int k, int stride) {
  Conv2dParams p;
  p.cin = cin, p.cout = cout, p.kh = p.kw = k, p.stride_h = p.stride_w = stride, p.pad_h = p.pad_w = k / 2;
  return p;
}

std::string block_name(const std::string& prefix, int layer, int i) {
  return prefix + "layer" + std::to_string(layer + 1) + "." + std::to_string(i) + ".";
}

// Calls f(layer, block, cin, width, stride) for every bottleneck.
template <typename F>
void for_each_block(F f) {
  int cin = 64;
  for (int l = 0; l < 4; ++l) {
    const int width = 64 << l;
    for (int i = 0; i < kBlocks[l]; ++i) {
      f(l, i, cin, width, (i == 0 && l > 0) ? 2 : 1);
      cin = 4 * width;
    }
  }
}

}  // namespace

std::vector<weights::TensorSpec> ResNet50Backbone::tensor_specs(const std::string& prefix) {
  std::vector<weights::TensorSpec> s;
  add_conv_bn_specs(s, prefix + "conv1.weight", prefix + "bn1.", {64, 3, 7, 7});
  for_each_block([&](int l, int i, int cin, int w, int) {
    const std::string b = block_name(prefix, l, i);
    add_conv_bn_specs(s, b + "conv1.weight", b + "bn1.", {w, cin, 1, 1});
    add_conv_bn_specs(s, b + "conv2.weight", b + "bn2.", {w, w, 3, 3});
    add_conv_bn_specs(s, b + "conv3.weight", b + "bn3.", {4 * w, w, 1, 1});
    if (i == 0) add_conv_bn_specs(s, b + "downsample.0.weight", b + "downsample.1.", {4 * w, cin, 1, 1});
  });
  return s;
}

ResNet50Backbone::ResNet50Backbone(const weights::SafeTensors& st, const std::string& prefix, float eps) {
  stem_ = load_conv_bn(st, prefix + "conv1.weight", prefix + "bn1.", conv(3, 64, 7, 2), eps);
  layers_.resize(4);
  for_each_block([&](int l, int i, int cin, int w, int stride) {
    const std::string b = block_name(prefix, l, i);
    Bottleneck blk;
    blk.conv1 = load_conv_bn(st, b + "conv1.weight", b + "bn1.", conv(cin, w, 1, 1), eps);
    blk.conv2 = load_conv_bn(st, b + "conv2.weight", b + "bn2.", conv(w, w, 3, stride), eps);
    blk.conv3 = load_conv_bn(st, b + "conv3.weight", b + "bn3.", conv(w, 4 * w, 1, 1), eps);
    blk.has_downsample = i == 0;
    if (blk.has_downsample)
      blk.downsample = load_conv_bn(st, b + "downsample.0.weight", b + "downsample.1.", conv(cin, 4 * w, 1, stride), eps);
    layers_[l].push_back(std::move(blk));
  });
}

void ResNet50Backbone::plan(int h, int w) {
  scratch_ = ConvScratch();
  Shape s = conv2d_output_shape({1, h, w, 3}, stem_.params());
  scratch_.require(stem_.params(), s.w);
  stem_out_.resize(s);
  s = max_pool2d_output_shape(s, MaxPoolParams{});
  pooled_.resize(s);
  for (auto& layer : layers_)
    for (Bottleneck& b : layer) {
      const Shape a = conv2d_output_shape(s, b.conv1.params());
      b.a.resize(a);
      const Shape c2 = conv2d_output_shape(a, b.conv2.params());
      b.b.resize(c2);
      const Shape o = conv2d_output_shape(c2, b.conv3.params());
      b.out.resize(o);
      if (b.has_downsample) b.identity.resize(conv2d_output_shape(s, b.downsample.params()));
      scratch_.require(b.conv1.params(), a.w);
      scratch_.require(b.conv2.params(), c2.w);
      scratch_.require(b.conv3.params(), o.w);
      if (b.has_downsample) scratch_.require(b.downsample.params(), o.w);
      s = o;
    }
  scratch_.allocate();
  outs_.reserve(layers_.size());
}

const std::vector<ConstTensorView>& ResNet50Backbone::forward(const ConstTensorView& in) {
  conv2d(in, stem_, stem_out_.view(), scratch_.get(), Act::Relu);
  max_pool2d(stem_out_.cview(), MaxPoolParams{}, pooled_.view());
  ConstTensorView x = pooled_.cview();
  outs_.clear();
  for (auto& layer : layers_) {
    for (Bottleneck& b : layer) {
      conv2d(x, b.conv1, b.a.view(), scratch_.get(), Act::Relu);
      conv2d(b.a.cview(), b.conv2, b.b.view(), scratch_.get(), Act::Relu);
      const float* identity = x.data;
      if (b.has_downsample) {
        conv2d(x, b.downsample, b.identity.view(), scratch_.get());
        identity = b.identity.data.data();
      }
      // relu(bn3(conv3) + identity): the epilogue's act_after_residual.
      conv2d(b.b.cview(), b.conv3, b.out.view(), scratch_.get(), Act::Relu, identity, true);
      x = b.out.cview();
    }
    outs_.push_back(x);
  }
  return outs_;
}

}  // namespace nn::detection
