#include "nn/models/detection/mobilenet_v3.h"

#include <algorithm>

#include "nn/activation.h"
#include "nn/error.h"
#include "nn/channel_scale.h"
#include "nn/pool.h"

namespace nn::detection {

namespace {

struct BlockSpec {
  int cin, k, exp, cout;
  bool se;
  Act act;
  int stride;
};

// torchvision mobilenetv3.py _mobilenet_v3_conf("mobilenet_v3_large"), features 1..15.
constexpr BlockSpec kLarge[] = {
    {16, 3, 16, 16, false, Act::Relu, 1},       {16, 3, 64, 24, false, Act::Relu, 2},
    {24, 3, 72, 24, false, Act::Relu, 1},       {24, 5, 72, 40, true, Act::Relu, 2},
    {40, 5, 120, 40, true, Act::Relu, 1},       {40, 5, 120, 40, true, Act::Relu, 1},
    {40, 3, 240, 80, false, Act::HardSwish, 2}, {80, 3, 200, 80, false, Act::HardSwish, 1},
    {80, 3, 184, 80, false, Act::HardSwish, 1}, {80, 3, 184, 80, false, Act::HardSwish, 1},
    {80, 3, 480, 112, true, Act::HardSwish, 1}, {112, 3, 672, 112, true, Act::HardSwish, 1},
    {112, 5, 672, 160, true, Act::HardSwish, 2}, {160, 5, 960, 160, true, Act::HardSwish, 1},
    {160, 5, 960, 160, true, Act::HardSwish, 1},
};
constexpr int kStem = 16, kLast = 960;

int make_divisible(double v) {
  int n = std::max(8, static_cast<int>(v + 4) / 8 * 8);
  if (n < 0.9 * v) n += 8;
  return n;
}

Conv2dParams conv_params(int cin, int cout, int k, int stride) {
  Conv2dParams p;
  p.cin = cin, p.cout = cout, p.kh = p.kw = k, p.stride_h = p.stride_w = stride, p.pad_h = p.pad_w = (k - 1) / 2;
  return p;
}

std::string block_prefix(const std::string& prefix, int i) { return prefix + std::to_string(i) + ".block."; }

}  // namespace

std::vector<weights::TensorSpec> MobileNetV3Backbone::tensor_specs(const std::string& prefix) {
  std::vector<weights::TensorSpec> s;
  add_conv_bn_specs(s, prefix + "0.0.weight", prefix + "0.1.", {kStem, 3, 3, 3});
  for (int i = 1; i <= 15; ++i) {
    const BlockSpec& b = kLarge[i - 1];
    const std::string p = block_prefix(prefix, i);
    int part = 0;
    if (b.exp != b.cin) {
      add_conv_bn_specs(s, p + "0.0.weight", p + "0.1.", {b.exp, b.cin, 1, 1});
      ++part;
    }
    const std::string dw = p + std::to_string(part++) + ".";
    add_conv_bn_specs(s, dw + "0.weight", dw + "1.", {b.exp, 1, b.k, b.k});
    if (b.se) {
      const std::string se = p + std::to_string(part++) + ".";
      const int sq = make_divisible(b.exp / 4);
      s.push_back({se + "fc1.weight", {sq, b.exp, 1, 1}});
      s.push_back({se + "fc1.bias", {sq}});
      s.push_back({se + "fc2.weight", {b.exp, sq, 1, 1}});
      s.push_back({se + "fc2.bias", {b.exp}});
    }
    const std::string pr = p + std::to_string(part) + ".";
    add_conv_bn_specs(s, pr + "0.weight", pr + "1.", {b.cout, b.exp, 1, 1});
  }
  add_conv_bn_specs(s, prefix + "16.0.weight", prefix + "16.1.", {kLast, 160, 1, 1});
  return s;
}

MobileNetV3Backbone::MobileNetV3Backbone(const weights::SafeTensors& st, const std::string& prefix, float eps)
    : prefix_(prefix) {
  stem_ = load_conv_bn(st, prefix + "0.0.weight", prefix + "0.1.", conv_params(3, kStem, 3, 2), eps);
  for (int i = 1; i <= 15; ++i) {
    const BlockSpec& s = kLarge[i - 1];
    Block b;
    b.cin = s.cin, b.exp = s.exp, b.cout = s.cout, b.k = s.k, b.stride = s.stride, b.act = s.act;
    b.has_expand = s.exp != s.cin;
    b.residual = s.stride == 1 && s.cin == s.cout;
    const std::string p = block_prefix(prefix, i);
    int part = 0;
    if (b.has_expand) {
      b.expand = load_conv_bn(st, p + "0.0.weight", p + "0.1.", conv_params(s.cin, s.exp, 1, 1), eps);
      ++part;
    }
    DwConvParams dp;
    dp.kh = dp.kw = s.k, dp.stride_h = dp.stride_w = s.stride, dp.pad_h = dp.pad_w = (s.k - 1) / 2, dp.act = s.act;
    const std::string dw = p + std::to_string(part++) + ".";
    b.dw = load_dwconv_bn(st, dw + "0.weight", dw + "1.", s.exp, dp, eps);
    if (s.se) {
      const std::string se = p + std::to_string(part++) + ".";
      b.se = make_divisible(s.exp / 4);
      const auto w1 = st.f32(se + "fc1.weight"), w2 = st.f32(se + "fc2.weight");
      const auto b1 = st.f32(se + "fc1.bias"), b2 = st.f32(se + "fc2.bias");
      b.fc1 = GemmWeights::pack(w1.data(), b.se, s.exp);
      b.fc2 = GemmWeights::pack(w2.data(), s.exp, b.se);
      b.fc1_bias.resize(b1.size());
      std::copy(b1.begin(), b1.end(), b.fc1_bias.data());
      b.fc2_bias.resize(b2.size());
      std::copy(b2.begin(), b2.end(), b.fc2_bias.data());
    }
    const std::string pr = p + std::to_string(part) + ".";
    b.project = load_conv_bn(st, pr + "0.weight", pr + "1.", conv_params(s.exp, s.cout, 1, 1), eps);
    blocks_.push_back(std::move(b));
  }
  last_ = load_conv_bn(st, prefix + "16.0.weight", prefix + "16.1.", conv_params(160, kLast, 1, 1), eps);
}

// torchvision's return_layers: the FPN reads the output of features[13] (block index 12).
constexpr std::size_t kC13Block = 12;

void MobileNetV3Backbone::plan(int h, int w, Profiler* prof) {
  prof_ = prof;
  std::size_t a_max = 0, b_max = 0, pp_max = 0;
  auto grow = [](std::size_t& m, const Shape& s) { m = std::max(m, s.count()); };
  Shape s = stem_shape_ = conv2d_output_shape({1, h, w, 3}, stem_.params());
  grow(pp_max, s);
  stem_name_ = prefix_ + "0";
  last_name_ = prefix_ + "16";
  row_stem_ = add_conv_row(prof, stem_name_, stem_, s);
  scratch_ = ConvScratch();
  scratch_.require(stem_, s.w);
  for (std::size_t i = 0; i < blocks_.size(); ++i) {
    Block& b = blocks_[i];
    // InvertedResidual.block: [expand], depthwise, [squeeze-excitation], project.
    int part = 0;
    b.name = prefix_ + std::to_string(i + 1);
    auto next = [&] { return b.name + ".block." + std::to_string(part++); };
    if (b.has_expand) {
      scratch_.require(b.expand, s.w);
      b.a = {1, s.h, s.w, b.exp};
      grow(a_max, b.a);
      b.expand_name = next();
      b.row_expand = add_conv_row(prof, b.expand_name, b.expand, b.a);
    }
    s = dwconv_output_shape({1, s.h, s.w, b.exp}, b.dw.params());
    b.b = s;
    grow(b_max, s);
    const std::string dw_name = b.dw_name = next();
    if (prof) {
      const DwConvParams& d = b.dw.params();
      b.row_dw = prof->add(dw_name, "dwconv " + std::to_string(d.kh) + "x" + std::to_string(d.kw) + "/" +
                                            std::to_string(d.stride_h),
                           nchw_str(s), 2.0 * s.count() * d.kh * d.kw);
    }
    if (b.se) {
      b.pooled.resize({1, 1, 1, b.exp});
      b.squeezed.resize({1, 1, 1, b.se});
      b.excited.resize({1, 1, 1, b.exp});
      const std::string se_name = b.se_name = next();
      if (prof) b.row_se = prof->add(se_name, "squeeze-excitation", nchw_str(s), 0);
    }
    scratch_.require(b.project, s.w);
    s.c = b.cout;
    b.out = s;
    b.project_name = next();
    b.row_project = add_conv_row(prof, b.project_name, b.project, s);
    if (i == kC13Block) c13_out_.resize(s);
    else grow(pp_max, s);
  }
  if (blocks_.size() <= kC13Block) throw Error("MobileNetV3: fewer blocks than the FPN reads");
  tmp_a_.resize(a_max);
  tmp_b_.resize(b_max);
  for (auto& buf : pingpong_) buf.resize(pp_max);
  scratch_.require(last_, s.w);
  last_out_.resize({1, s.h, s.w, kLast});
  row_last_ = add_conv_row(prof, last_name_, last_, last_out_.shape);
  scratch_.allocate();
  outs_.reserve(2);
}

void MobileNetV3Backbone::run_block(Block& b, const ConstTensorView& in, const TensorView& out) {
  ConstTensorView x = in;
  if (b.has_expand) {
    const TensorView a{tmp_a_.data(), b.a};
    conv2d_timed(prof_, b.row_expand, x, b.expand, a, scratch_.get(), b.act);
    if (dump_) dump_nhwc(dump_, b.expand_name, a);
    x = a;
  }
  const TensorView mid{tmp_b_.data(), b.b};
  {
    Profiler::Scope t(prof_, b.row_dw);
    dwconv(x, b.dw, mid);
  }
  if (dump_) dump_nhwc(dump_, b.dw_name, mid);
  if (b.se) {
    Profiler::Scope t(prof_, b.row_se);
    // Squeeze-excitation: hardsigmoid(fc2(relu(fc1(mean)))) scales every pixel.
    global_avg_pool(mid, b.pooled.view());
    GemmEpilogue e1;
    e1.bias = b.fc1_bias.data(), e1.act = Act::Relu;
    gemm(1, b.pooled.data.data(), b.exp, b.fc1, b.squeezed.data.data(), b.se, e1);
    GemmEpilogue e2;
    e2.bias = b.fc2_bias.data(), e2.act = Act::HardSigmoid;
    gemm(1, b.squeezed.data.data(), b.se, b.fc2, b.excited.data.data(), b.exp, e2);
    scale_channels(mid, b.excited.data.data());
  }
  if (dump_ && b.se) dump_nhwc(dump_, b.se_name, mid);
  conv2d_timed(prof_, b.row_project, mid, b.project, out, scratch_.get(), Act::None, b.residual ? in.data : nullptr);
  if (dump_) {
    // With a residual the add is fused into the projection: its own output does not exist.
    const std::string sequential = b.name + ".block";  // the block's Sequential: the projection
    if (!b.residual) {
      dump_nhwc(dump_, b.project_name, out);
      dump_nhwc(dump_, sequential, out);
    }
    dump_nhwc(dump_, b.name, out, b.residual ? b.project_name + "," + sequential : std::string());
  }
}

const std::vector<ConstTensorView>& MobileNetV3Backbone::forward(const ConstTensorView& in) {
  const TensorView stem_out{pingpong_[0].data(), stem_shape_};
  conv2d_timed(prof_, row_stem_, in, stem_, stem_out, scratch_.get(), Act::HardSwish);
  if (dump_) dump_nhwc(dump_, stem_name_, stem_out);
  ConstTensorView x = stem_out;
  int next = 1;  // the ping-pong buffer the next block writes (never x's)
  for (std::size_t i = 0; i < blocks_.size(); ++i) {
    const TensorView out = i == kC13Block ? c13_out_.view() : TensorView{pingpong_[next].data(), blocks_[i].out};
    run_block(blocks_[i], x, out);
    x = out;
    if (i != kC13Block) next ^= 1;
  }
  conv2d_timed(prof_, row_last_, x, last_, last_out_.view(), scratch_.get(), Act::HardSwish);
  if (dump_) dump_nhwc(dump_, last_name_, last_out_.cview());
  outs_.assign({c13_out_.cview(), last_out_.cview()});
  return outs_;
}

}  // namespace nn::detection
