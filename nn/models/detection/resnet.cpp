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

std::string stage_name(const std::string& prefix, WeightLayout layout, int layer) {
  return layout == WeightLayout::Detectron2 ? prefix + "res" + std::to_string(layer + 2)
                                            : prefix + "layer" + std::to_string(layer + 1);
}

std::string block_name(const std::string& prefix, WeightLayout layout, int layer, int i) {
  return stage_name(prefix, layout, layer) + "." + std::to_string(i) + ".";
}

// A conv weight and the prefix of its frozen batch norm.
struct ConvBn {
  std::string weight, bn;
};

// conv k (1..3) of a block; k = 0: the projection shortcut.
ConvBn conv_bn(const std::string& block, WeightLayout layout, int k) {
  if (layout == WeightLayout::Detectron2) {
    const std::string conv = block + (k ? "conv" + std::to_string(k) : std::string("shortcut"));
    return {conv + ".weight", conv + ".norm."};
  }
  if (k == 0) return {block + "downsample.0.weight", block + "downsample.1."};
  return {block + "conv" + std::to_string(k) + ".weight", block + "bn" + std::to_string(k) + "."};
}

ConvBn stem_conv_bn(const std::string& prefix, WeightLayout layout) {
  if (layout == WeightLayout::Detectron2) return {prefix + "stem.conv1.weight", prefix + "stem.conv1.norm."};
  return {prefix + "conv1.weight", prefix + "bn1."};
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

std::vector<weights::TensorSpec> ResNet50Backbone::tensor_specs(const std::string& prefix, WeightLayout layout) {
  std::vector<weights::TensorSpec> s;
  const ConvBn stem = stem_conv_bn(prefix, layout);
  add_conv_bn_specs(s, stem.weight, stem.bn, {64, 3, 7, 7});
  for_each_block([&](int l, int i, int cin, int w, int) {
    const std::string b = block_name(prefix, layout, l, i);
    // detectron2's checkpoint lists the shortcut first, torchvision's state_dict last.
    if (i == 0 && layout == WeightLayout::Detectron2) {
      const ConvBn c = conv_bn(b, layout, 0);
      add_conv_bn_specs(s, c.weight, c.bn, {4 * w, cin, 1, 1});
    }
    const Dims shapes[3] = {{w, cin, 1, 1}, {w, w, 3, 3}, {4 * w, w, 1, 1}};
    for (int k = 1; k <= 3; ++k) {
      const ConvBn c = conv_bn(b, layout, k);
      add_conv_bn_specs(s, c.weight, c.bn, shapes[k - 1]);
    }
    if (i == 0 && layout == WeightLayout::Torchvision) {
      const ConvBn c = conv_bn(b, layout, 0);
      add_conv_bn_specs(s, c.weight, c.bn, {4 * w, cin, 1, 1});
    }
  });
  return s;
}

ResNet50Backbone::ResNet50Backbone(const weights::SafeTensors& st, const std::string& prefix, float eps,
                                   WeightLayout layout) {
  const bool d2 = layout == WeightLayout::Detectron2;
  const ConvBn stem = stem_conv_bn(prefix, layout);
  stem_ = load_conv_bn(st, stem.weight, stem.bn, conv(3, 64, 7, 2), eps);
  // detectron2's BasicStem returns after its max pool, its ReLU is functional.
  stem_name_ = d2 ? "" : prefix + "relu";
  stem_row_ = d2 ? prefix + "stem.conv1" : stem_name_;
  stem_covers_ = module_list(prefix, {"conv1", "bn1"});
  pool_name_ = d2 ? prefix + "stem" : prefix + "maxpool";
  for (int l = 0; l < 4; ++l) layer_names_.push_back(stage_name(prefix, layout, l));
  layers_.resize(4);
  for_each_block([&](int l, int i, int cin, int w, int stride) {
    const std::string b = block_name(prefix, layout, l, i);
    Bottleneck blk;
    blk.name = b.substr(0, b.size() - 1);
    if (!d2) {  // detectron2's ReLUs are functional: no module returns them
      blk.relu1 = b + "relu";
      blk.relu2 = b + "relu#1";
      blk.relu3 = b + "relu#2";
    }
    const ConvBn c1 = conv_bn(b, layout, 1), c2 = conv_bn(b, layout, 2), c3 = conv_bn(b, layout, 3),
                 c0 = conv_bn(b, layout, 0);
    auto covers = [](const ConvBn& c) {
      return c.weight.substr(0, c.weight.size() - 7) + "," + c.bn.substr(0, c.bn.size() - 1);
    };
    blk.down = c0.weight.substr(0, c0.weight.size() - 7);
    if (!d2) blk.down = b + "downsample";
    blk.row1 = d2 ? c1.weight.substr(0, c1.weight.size() - 7) : blk.relu1;
    blk.row2 = d2 ? c2.weight.substr(0, c2.weight.size() - 7) : blk.relu2;
    blk.covers1 = covers(c1);
    blk.covers2 = covers(c2);
    blk.covers3 = covers(c3);  // + the residual add
    blk.covers_down = covers(c0);
    // STRIDE_IN_1X1 puts the stage's stride in conv1; torchvision (v1.5) in conv2.
    const int s1 = d2 ? stride : 1, s2 = d2 ? 1 : stride;
    blk.conv1 = load_conv_bn(st, c1.weight, c1.bn, conv(cin, w, 1, s1), eps);
    blk.conv2 = load_conv_bn(st, c2.weight, c2.bn, conv(w, w, 3, s2), eps);
    blk.conv3 = load_conv_bn(st, c3.weight, c3.bn, conv(w, 4 * w, 1, 1), eps);
    blk.has_downsample = i == 0;
    if (blk.has_downsample) blk.downsample = load_conv_bn(st, c0.weight, c0.bn, conv(cin, 4 * w, 1, stride), eps);
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
  row_stem_ = add_conv_row(prof, stem_row_, stem_, s);
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
      b.prow1 = add_conv_row(prof, b.row1, b.conv1, b.a);
      b.prow2 = add_conv_row(prof, b.row2, b.conv2, b.b);
      if (b.has_downsample) b.prow_down = add_conv_row(prof, b.down, b.downsample, b.out);
      b.prow3 = add_conv_row(prof, b.name, b.conv3, b.out);
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
    if (!stem_name_.empty()) dump_nhwc(dump_, stem_name_, stem_out, stem_covers_);
    dump_nhwc(dump_, pool_name_, pooled_.cview());
  }
  ConstTensorView x = pooled_.cview();
  int next = 0;  // the ping-pong buffer the next inner block writes (never x's)
  outs_.clear();
  for (std::size_t l = 0; l < layers_.size(); ++l) {
    for (std::size_t i = 0; i < layers_[l].size(); ++i) {
      Bottleneck& b = layers_[l][i];
      const TensorView a{tmp_a_.data(), b.a}, mid{tmp_b_.data(), b.b};
      conv2d_timed(prof_, b.prow1, x, b.conv1, a, scratch_.get(), Act::Relu);
      if (dump_ && !b.relu1.empty()) dump_nhwc(dump_, b.relu1, a, b.covers1);
      conv2d_timed(prof_, b.prow2, a, b.conv2, mid, scratch_.get(), Act::Relu);
      if (dump_ && !b.relu2.empty()) dump_nhwc(dump_, b.relu2, mid, b.covers2);
      const float* identity = x.data;
      if (b.has_downsample) {
        conv2d_timed(prof_, b.prow_down, x, b.downsample, TensorView{tmp_identity_.data(), b.out}, scratch_.get());
        identity = tmp_identity_.data();
        if (dump_) dump_nhwc(dump_, b.down, ConstTensorView(identity, b.out), b.covers_down);
      }
      const bool last = i + 1 == layers_[l].size();
      const TensorView out = last ? layer_out_[l].view() : TensorView{pingpong_[next].data(), b.out};
      // relu(bn3(conv3) + identity): the epilogue's act_after_residual.
      conv2d_timed(prof_, b.prow3, mid, b.conv3, out, scratch_.get(), Act::Relu, identity, true);
      x = ConstTensorView(out.data, out.shape);
      if (dump_) {
        if (!b.relu3.empty()) dump_nhwc(dump_, b.relu3, x, b.covers3);
        dump_nhwc(dump_, b.name, x, b.relu3.empty() ? b.covers3 : b.covers3 + "," + b.relu3);
      }
      if (!last) next ^= 1;
    }
    if (dump_) dump_nhwc(dump_, layer_names_[l], x);
    outs_.push_back(x);
  }
  return outs_;
}

}  // namespace nn::detection
