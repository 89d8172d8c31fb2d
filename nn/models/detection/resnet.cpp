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
  stem_name_ = prefix + "relu";
  stem_covers_ = module_list(prefix, {"conv1", "bn1"});
  pool_name_ = prefix + "maxpool";
  for (int l = 0; l < 4; ++l) layer_names_.push_back(prefix + "layer" + std::to_string(l + 1));
  layers_.resize(4);
  for_each_block([&](int l, int i, int cin, int w, int stride) {
    const std::string b = block_name(prefix, l, i);
    Bottleneck blk;
    blk.name = b.substr(0, b.size() - 1);
    blk.relu1 = b + "relu";
    blk.relu2 = b + "relu#1";
    blk.relu3 = b + "relu#2";
    blk.down = b + "downsample";
    blk.covers1 = module_list(b, {"conv1", "bn1"});
    blk.covers2 = module_list(b, {"conv2", "bn2"});
    blk.covers3 = module_list(b, {"conv3", "bn3"});  // + the residual add
    blk.covers_down = module_list(b, {"downsample.0", "downsample.1"});
    blk.conv1 = load_conv_bn(st, b + "conv1.weight", b + "bn1.", conv(cin, w, 1, 1), eps);
    blk.conv2 = load_conv_bn(st, b + "conv2.weight", b + "bn2.", conv(w, w, 3, stride), eps);
    blk.conv3 = load_conv_bn(st, b + "conv3.weight", b + "bn3.", conv(w, 4 * w, 1, 1), eps);
    blk.has_downsample = i == 0;
    if (blk.has_downsample)
      blk.downsample = load_conv_bn(st, b + "downsample.0.weight", b + "downsample.1.", conv(cin, 4 * w, 1, stride), eps);
    layers_[l].push_back(std::move(blk));
  });
}

void ResNet50Backbone::plan(int h, int w, Profiler* prof) {
  prof_ = prof;
  scratch_ = ConvScratch();
  std::size_t a_max = 0, b_max = 0, id_max = 0, pp_max = 0;
  auto grow = [](std::size_t& m, const Shape& s) { m = std::max(m, s.count()); };
  Shape s = stem_shape_ = conv2d_output_shape({1, h, w, 3}, stem_.params());
  scratch_.require(stem_, s.w);
  grow(pp_max, s);
  row_stem_ = add_conv_row(prof, stem_name_, stem_, s);
  s = max_pool2d_output_shape(s, MaxPoolParams{});
  pooled_.resize(s);
  if (prof) row_pool_ = prof->add(pool_name_, "max pool 3x3/2", nchw_str(s), 0);
  layer_out_.resize(layers_.size());
  for (std::size_t l = 0; l < layers_.size(); ++l) {
    for (std::size_t i = 0; i < layers_[l].size(); ++i) {
      Bottleneck& b = layers_[l][i];
      b.a = conv2d_output_shape(s, b.conv1.params());
      b.b = conv2d_output_shape(b.a, b.conv2.params());
      b.out = conv2d_output_shape(b.b, b.conv3.params());
      grow(a_max, b.a);
      grow(b_max, b.b);
      if (b.has_downsample) grow(id_max, conv2d_output_shape(s, b.downsample.params()));
      // Rows under the dump's names: each fused conv's output tensor.
      b.row1 = add_conv_row(prof, b.relu1, b.conv1, b.a);
      b.row2 = add_conv_row(prof, b.relu2, b.conv2, b.b);
      if (b.has_downsample) b.row_down = add_conv_row(prof, b.down, b.downsample, b.out);
      b.row3 = add_conv_row(prof, b.name, b.conv3, b.out);
      if (i + 1 < layers_[l].size()) grow(pp_max, b.out);
      scratch_.require(b.conv1, b.a.w);
      scratch_.require(b.conv2, b.b.w);
      scratch_.require(b.conv3, b.out.w);
      if (b.has_downsample) scratch_.require(b.downsample, b.out.w);
      s = b.out;
    }
    layer_out_[l].resize(s);
  }
  tmp_a_.resize(a_max);
  tmp_b_.resize(b_max);
  tmp_identity_.resize(id_max);
  for (auto& buf : pingpong_) buf.resize(pp_max);
  scratch_.allocate();
  outs_.reserve(layers_.size());
}

const std::vector<ConstTensorView>& ResNet50Backbone::forward(const ConstTensorView& in) {
  const TensorView stem_out{pingpong_[0].data(), stem_shape_};
  conv2d_timed(prof_, row_stem_, in, stem_, stem_out, scratch_.get(), Act::Relu);
  {
    Profiler::Scope t(prof_, row_pool_);
    max_pool2d(ConstTensorView(stem_out.data, stem_out.shape), MaxPoolParams{}, pooled_.view());
  }
  if (dump_) {
    dump_nhwc(dump_, stem_name_, stem_out, stem_covers_);
    dump_nhwc(dump_, pool_name_, pooled_.cview());
  }
  ConstTensorView x = pooled_.cview();
  int next = 0;  // the ping-pong buffer the next inner block writes (never x's)
  outs_.clear();
  for (std::size_t l = 0; l < layers_.size(); ++l) {
    for (std::size_t i = 0; i < layers_[l].size(); ++i) {
      Bottleneck& b = layers_[l][i];
      const TensorView a{tmp_a_.data(), b.a}, mid{tmp_b_.data(), b.b};
      conv2d_timed(prof_, b.row1, x, b.conv1, a, scratch_.get(), Act::Relu);
      if (dump_) dump_nhwc(dump_, b.relu1, a, b.covers1);
      conv2d_timed(prof_, b.row2, a, b.conv2, mid, scratch_.get(), Act::Relu);
      if (dump_) dump_nhwc(dump_, b.relu2, mid, b.covers2);
      const float* identity = x.data;
      if (b.has_downsample) {
        conv2d_timed(prof_, b.row_down, x, b.downsample, TensorView{tmp_identity_.data(), b.out}, scratch_.get());
        identity = tmp_identity_.data();
        if (dump_) dump_nhwc(dump_, b.down, ConstTensorView(identity, b.out), b.covers_down);
      }
      const bool last = i + 1 == layers_[l].size();
      const TensorView out = last ? layer_out_[l].view() : TensorView{pingpong_[next].data(), b.out};
      // relu(bn3(conv3) + identity): the epilogue's act_after_residual.
      conv2d_timed(prof_, b.row3, mid, b.conv3, out, scratch_.get(), Act::Relu, identity, true);
      x = ConstTensorView(out.data, out.shape);
      if (dump_) {
        dump_nhwc(dump_, b.relu3, x, b.covers3);
        dump_nhwc(dump_, b.name, x, b.covers3 + "," + b.relu3);
      }
      if (!last) next ^= 1;
    }
    if (dump_) dump_nhwc(dump_, layer_names_[l], x);
    outs_.push_back(x);
  }
  return outs_;
}

}  // namespace nn::detection
