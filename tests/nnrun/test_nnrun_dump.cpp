// nnrun --dump / --dump-filter, --model stixelnext and --profile --format json|csv as
// users drive them (issue 16): the dump's names, order, layout and metadata, its output
// file going through the same refusals as --output, and machine-readable timings whose
// layer names are the dump's.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "nn/layout.h"
#include "nn/models/convnext.h"
#include "nn/models/stixel_head.h"
#include "nn/models/synthetic_weights.h"
#include "weights/json.h"
#include "weights/safetensors.h"

namespace {

// Odd widths, two blocks in stage 3, so names and shapes are not all alike.
nn::ConvNeXtConfig small_config() { return {{8, 12, 20, 28}, {1, 1, 2, 1}}; }

struct Result {
  int code = -1;
  std::string err, out;
};

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::stringstream in(s);
  for (std::string part; std::getline(in, part, sep);) out.push_back(part);
  return out;
}

class NnrunDump : public testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/nnrun_dump_XXXXXX";
    ASSERT_NE(mkdtemp(tmpl), nullptr);
    dir_ = tmpl;
    nn::synthetic_weights(nn::convnext_tensor_specs(small_config(), "features."), 3).write(path("w.safetensors"));
    std::vector<float> x(3 * 64 * 96);
    for (std::size_t i = 0; i < x.size(); ++i) x[i] = static_cast<float>((i * 37) % 101) / 50.0f - 1.0f;
    weights::Writer in;
    in.add_f32("input", {1, 3, 64, 96}, x.data());
    in.write(path("x.safetensors"));
  }
  void TearDown() override { std::system(("rm -rf " + dir_).c_str()); }

  std::string path(const std::string& f) const { return dir_ + "/" + f; }
  bool exists(const std::string& f) const { return std::ifstream(path(f)).good(); }

  Result run(const std::string& extra, const std::string& model = "convnext", const std::string& weights = "w.safetensors") {
    const std::string cmd = std::string(NNRUN_PATH) + " --model " + model + " --weights " + path(weights) +
                            " --input " + path("x.safetensors") + " --output " + path("y.safetensors") +
                            " --threads 2 --quiet " + extra + " >" + path("stdout") + " 2>" + path("stderr");
    Result r;
    const int status = std::system(cmd.c_str());
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    std::stringstream e, o;
    e << std::ifstream(path("stderr")).rdbuf();
    o << std::ifstream(path("stdout")).rdbuf();
    r.err = e.str();
    r.out = o.str();
    return r;
  }

  // Every name the small ConvNeXt dumps, in network order.
  static std::vector<std::string> convnext_names() {
    std::vector<std::string> n = {"features.0"};
    const auto cfg = small_config();
    for (std::size_t s = 0; s < cfg.dims.size(); ++s) {
      if (s > 0) n.push_back("features." + std::to_string(2 * s));
      const std::string stage = "features." + std::to_string(2 * s + 1);
      for (int b = 0; b < cfg.depths[s]; ++b) {
        for (int layer = 0; layer <= 4; ++layer)  // depthwise, then the MLP up to its GELU
          n.push_back(stage + "." + std::to_string(b) + ".block." + std::to_string(layer));
        n.push_back(stage + "." + std::to_string(b));
      }
      n.push_back(stage);
    }
    n.push_back("features");
    return n;
  }

  std::string dir_;
};

TEST_F(NnrunDump, ConvNeXtEveryBlockInNetworkOrderWithMetadata) {
  Result r = run("--dump " + path("d.safetensors"));
  ASSERT_EQ(r.code, 0) << r.err;
  weights::SafeTensors d = weights::SafeTensors::load(path("d.safetensors"));
  weights::SafeTensors y = weights::SafeTensors::load(path("y.safetensors"));
  const auto& meta = d.metadata();
  EXPECT_EQ(meta.at("dump.source"), "roadnn");
  EXPECT_EQ(meta.at("dump.model"), "convnext");
  EXPECT_EQ(meta.at("dump.path").rfind("fused, plus for the dump", 0), 0u) << meta.at("dump.path");
  EXPECT_EQ(split(meta.at("dump.order"), ','), convnext_names());
  EXPECT_EQ(d.names().size(), convnext_names().size());
  EXPECT_EQ(meta.at("dump.covers.features.0"), "features.0.0,features.0.1");
  EXPECT_EQ(meta.at("dump.covers.features.4"), "features.4.0,features.4.1");
  const auto covers = split(meta.at("dump.covers.features.5.1"), ',');
  for (const char* m : {"features.5.1.block", "features.5.1.block.5", "features.5.1.block.6",
                        "features.5.1.stochastic_depth"})
    EXPECT_NE(std::find(covers.begin(), covers.end(), m), covers.end()) << m;
  EXPECT_EQ(std::find(covers.begin(), covers.end(), "features.5.1.block.2"), covers.end()) << "dumped on its own";
  EXPECT_EQ(meta.count("dump.covers.features.5.1.block.0"), 0u);
  // NCHW as PyTorch returns them: stride 4 stem, 7x7 depthwise keeps the shape.
  EXPECT_EQ(d.info("features.0").shape, (std::vector<std::int64_t>{1, 8, 16, 24}));
  EXPECT_EQ(d.info("features.3.0.block.0").shape, (std::vector<std::int64_t>{1, 12, 8, 12}));
  EXPECT_EQ(d.info("features.7.0").shape, (std::vector<std::int64_t>{1, 28, 2, 3}));
  // Inside the permuted MLP, channels last as PyTorch has them: block.1 is block.0 permuted.
  EXPECT_EQ(d.info("features.3.0.block.1").shape, (std::vector<std::int64_t>{1, 8, 12, 12}));
  EXPECT_EQ(d.info("features.3.0.block.4").shape, (std::vector<std::int64_t>{1, 8, 12, 48}));
  {
    const auto nchw = d.f32("features.3.0.block.0"), nhwc = d.f32("features.3.0.block.1");
    for (int ch = 0; ch < 12; ++ch)
      for (int p = 0; p < 8 * 12; ++p) ASSERT_EQ(nchw[ch * 96 + p], nhwc[p * 12 + ch]) << ch << " " << p;
    // GELU of the Linear: negative inputs shrink towards zero, positive ones barely move.
    const auto pre = d.f32("features.3.0.block.3"), post = d.f32("features.3.0.block.4");
    for (std::size_t i = 0; i < pre.size(); ++i) {
      ASSERT_LE(post[i], std::max(pre[i], 0.0f) + 1e-6f) << i;
      ASSERT_GE(post[i], -0.17f) << i;
    }
  }
  // The last tensor is the model's output, bitwise (NCHW checked against --output); a
  // stage is its last block.
  EXPECT_TRUE(d.f32("features") == y.f32("features"));
  EXPECT_TRUE(d.f32("features.7") == d.f32("features.7.0"));
  EXPECT_TRUE(d.f32("features.5") == d.f32("features.5.1"));
  EXPECT_FALSE(d.f32("features.5.0") == d.f32("features.5.1"));
}

// --profile runs the engine's own runner, plain runs the public API: same dump bytes.
TEST_F(NnrunDump, ApiAndEngineRunnersDumpTheSameBits) {
  ASSERT_EQ(run("--dump " + path("a.safetensors")).code, 0);
  Result r = run("--dump " + path("b.safetensors") + " --profile");
  ASSERT_EQ(r.code, 0) << r.err;
  weights::SafeTensors a = weights::SafeTensors::load(path("a.safetensors"));
  weights::SafeTensors b = weights::SafeTensors::load(path("b.safetensors"));
  ASSERT_EQ(a.metadata().at("dump.order"), b.metadata().at("dump.order"));
  for (const auto& n : a.names()) EXPECT_TRUE(a.f32(n) == b.f32(n)) << n;
}

TEST_F(NnrunDump, FilterSearchesNames) {
  Result r = run("--dump " + path("d.safetensors") + " --dump-filter '^features\\.[0-9]+$'");
  ASSERT_EQ(r.code, 0) << r.err;
  weights::SafeTensors d = weights::SafeTensors::load(path("d.safetensors"));
  const std::vector<std::string> want = {"features.0", "features.1", "features.2", "features.3",
                                         "features.4", "features.5", "features.6", "features.7"};
  EXPECT_EQ(split(d.metadata().at("dump.order"), ','), want);
  // Search semantics: a bare fragment matches anywhere in the name.
  ASSERT_EQ(run("--dump " + path("e.safetensors") + " --dump-filter block").code, 0);
  weights::SafeTensors e = weights::SafeTensors::load(path("e.safetensors"));
  EXPECT_EQ(e.names().size(), 25u);  // block.0 .. block.4 of 5 blocks
  for (const auto& n : e.names()) EXPECT_NE(n.find(".block."), std::string::npos) << n;
}

TEST_F(NnrunDump, FilterErrorsWriteNothing) {
  Result bad = run("--dump " + path("d.safetensors") + " --dump-filter '(unclosed'");
  EXPECT_EQ(bad.code, 2) << bad.err;
  EXPECT_NE(bad.err.find("--dump-filter"), std::string::npos) << bad.err;
  Result none = run("--dump " + path("d.safetensors") + " --dump-filter '^nothing$'");
  EXPECT_EQ(none.code, 1) << none.err;
  EXPECT_NE(none.err.find("matches none"), std::string::npos) << none.err;
  EXPECT_EQ(std::count(none.err.begin(), none.err.end(), '\n'), 1) << none.err;
  EXPECT_FALSE(exists("d.safetensors"));
  EXPECT_FALSE(exists("y.safetensors"));
  Result alone = run("--dump-filter x");
  EXPECT_EQ(alone.code, 2);
  EXPECT_NE(alone.err.find("needs --dump"), std::string::npos) << alone.err;
}

TEST_F(NnrunDump, DumpMayNotReplaceAnInputOrTheOutput) {
  std::ifstream before(path("x.safetensors"), std::ios::binary);
  const std::string x_bytes((std::istreambuf_iterator<char>(before)), std::istreambuf_iterator<char>());
  Result r = run("--dump " + path("x.safetensors"));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("would overwrite the input"), std::string::npos) << r.err;
  std::ifstream after(path("x.safetensors"), std::ios::binary);
  EXPECT_EQ(x_bytes, std::string((std::istreambuf_iterator<char>(after)), std::istreambuf_iterator<char>()));
  Result w = run("--dump " + path("w.safetensors"));
  EXPECT_EQ(w.code, 1);
  EXPECT_NE(w.err.find("would overwrite"), std::string::npos) << w.err;
  Result o = run("--dump " + path("y.safetensors"));
  EXPECT_EQ(o.code, 1);
  EXPECT_NE(o.err.find("two outputs"), std::string::npos) << o.err;
  EXPECT_FALSE(exists("y.safetensors"));
}

// Every detector and StixelNExT++ dump too (synthetic weights; the values are checked
// against PyTorch in tests/reference).
TEST_F(NnrunDump, StixelNExTPredictionAndDump) {
  auto specs = nn::convnext_tensor_specs(small_config(), "features.");
  for (auto& s : nn::stixel_head_tensor_specs(nn::StixelHeadVariant::V4, 28, "classifier.")) specs.push_back(s);
  nn::synthetic_weights(specs, 5).write(path("s.safetensors"));
  Result r = run("--dump " + path("d.safetensors"), "stixelnext", "s.safetensors");
  ASSERT_EQ(r.code, 0) << r.err;
  weights::SafeTensors y = weights::SafeTensors::load(path("y.safetensors"));
  EXPECT_EQ(y.info("prediction").shape, (std::vector<std::int64_t>{1, 4, 64, 96 / 8}));
  weights::SafeTensors d = weights::SafeTensors::load(path("d.safetensors"));
  EXPECT_EQ(d.metadata().at("dump.model"), "stixelnext");
  const auto order = split(d.metadata().at("dump.order"), ',');
  EXPECT_EQ(order.back(), "classifier");
  EXPECT_TRUE(d.f32("classifier") == y.f32("prediction"));
  for (const char* n : {"features", "avgpool", "classifier.local_mixing.depthwise", "classifier.shared_reduce",
                        "classifier.up.0", "classifier.up.1", "classifier.up"})
    EXPECT_TRUE(d.has(n)) << n;
  EXPECT_EQ(d.info("avgpool").shape, (std::vector<std::int64_t>{1, 28, 1, 3}));
  EXPECT_EQ(d.info("classifier.up").shape, (std::vector<std::int64_t>{1, 256, 1, 12}));
  // The columns come from the metadata when it names them.
  weights::Writer with_columns = nn::synthetic_weights(specs, 5);
  with_columns.set_metadata("stixelnext.columns", "5");
  with_columns.write(path("s5.safetensors"));
  ASSERT_EQ(run("", "stixelnext", "s5.safetensors").code, 0);
  EXPECT_EQ(weights::SafeTensors::load(path("y.safetensors")).info("prediction").shape,
            (std::vector<std::int64_t>{1, 4, 64, 5}));
}

TEST_F(NnrunDump, ProfileJsonParsesAndNamesTheDumpsTensors) {
  Result r = run("--profile --repeat 3 --format json --dump " + path("d.safetensors"));
  ASSERT_EQ(r.code, 0) << r.err;
  const json::Value v = json::parse(r.out, "nnrun stdout");
  EXPECT_EQ(v.get("model")->str(), "convnext");
  EXPECT_EQ(v.get("passes")->number(), 3);
  EXPECT_GT(v.get("peak_gflops")->number(), 0);
  const auto& fwd = *v.get("forward_ms");
  EXPECT_LE(fwd.get("min")->number(), fwd.get("median")->number());
  EXPECT_LE(fwd.get("median")->number(), fwd.get("max")->number());
  weights::SafeTensors d = weights::SafeTensors::load(path("d.safetensors"));
  std::set<std::string> names;
  const auto& layers = v.get("layers")->array();
  ASSERT_FALSE(layers.empty());
  for (const auto& l : layers) {
    const std::string name = l.get("name")->str();
    names.insert(name);
    EXPECT_TRUE(d.has(name)) << "profiled layer '" << name << "' is not in the dump";
    EXPECT_EQ(l.get("calls")->number(), 3) << name;
    EXPECT_LE(l.get("ms_min")->number(), l.get("ms_median")->number()) << name;
    EXPECT_LE(l.get("ms_median")->number(), l.get("ms_max")->number()) << name;
    EXPECT_GT(l.get("flops")->number(), 0) << name;
    EXPECT_GT(l.get("bytes")->number(), 0) << name;
    EXPECT_TRUE(l.get("pct_peak")->is_number()) << name;
    EXPECT_FALSE(l.get("shape")->str().empty()) << name;
  }
  // Every stem, downsampling layer, depthwise conv and block has its row.
  for (const auto& n : convnext_names()) {
    const bool stage = n == "features" || n == "features.1" || n == "features.3" || n == "features.5" ||
                       n == "features.7";  // a stage is its last block: no row of its own
    const bool mlp_layer = n.find(".block.") != std::string::npos && n.find(".block.0") == std::string::npos;
    if (mlp_layer) continue;  // computed for the dump only; the fused tile's row is the block
    if (!stage) {
      EXPECT_TRUE(names.count(n)) << n;
    }
  }
}

// --warmup passes run before the timed ones and are not counted: every layer's call
// count is --repeat's. Without --repeat or --profile, or negative, it is a usage error.
TEST_F(NnrunDump, WarmupPassesAreNotTimed) {
  Result r = run("--profile --repeat 2 --warmup 3 --format json");
  ASSERT_EQ(r.code, 0) << r.err;
  const json::Value v = json::parse(r.out, "nnrun stdout");
  EXPECT_EQ(v.get("passes")->number(), 2);
  const auto& layers = v.get("layers")->array();
  ASSERT_FALSE(layers.empty());
  for (const auto& l : layers) EXPECT_EQ(l.get("calls")->number(), 2) << l.get("name")->str();
  for (const char* bad : {"--warmup 2", "--repeat 1 --warmup -1"}) {
    Result u = run(bad);
    EXPECT_EQ(u.code, 2) << bad << ": " << u.err;
    EXPECT_NE(u.err.find("--warmup"), std::string::npos) << u.err;
  }
}

TEST_F(NnrunDump, ProfileCsvAndProfileOut) {
  Result r = run("--profile --repeat 2 --format csv --profile-out " + path("t.csv"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("forward_ms min="), std::string::npos) << "text lines stay on stdout: " << r.out;
  std::ifstream f(path("t.csv"));
  std::vector<std::string> lines;
  for (std::string l; std::getline(f, l);) lines.push_back(l);
  ASSERT_GE(lines.size(), 2u);
  EXPECT_EQ(lines[0], "name,level,op,shape,flops,bytes,calls,ms_min,ms_median,ms_max,gflops,pct_peak");
  // stem + 3 downsampling layers + 5 blocks x (depthwise, MLP)
  EXPECT_EQ(lines.size(), 1u + 1 + 3 + 10);
  EXPECT_EQ(lines[1].rfind("features.0,model,", 0), 0u) << lines[1];
  for (std::size_t i = 1; i < lines.size(); ++i) {
    int fields = 1;
    bool quoted = false;  // the shape "[1, 8, 16, 24]" is one quoted field
    for (char c : lines[i]) {
      if (c == '"') quoted = !quoted;
      if (c == ',' && !quoted) ++fields;
    }
    EXPECT_EQ(fields, 12) << lines[i];
    EXPECT_NE(lines[i].find("\"["), std::string::npos) << lines[i];
  }
  Result usage = run("--format json");
  EXPECT_EQ(usage.code, 2);
  EXPECT_NE(usage.err.find("needs --profile"), std::string::npos) << usage.err;
  Result same = run("--profile --format json --profile-out " + path("y.safetensors"));
  EXPECT_EQ(same.code, 1);
  EXPECT_NE(same.err.find("two outputs"), std::string::npos) << same.err;
}

TEST_F(NnrunDump, HelpNamesTheNewOptionsAndStixelNExT) {
  Result r = run("--help");
  const std::string all = r.out + r.err;
  for (const char* s : {"--dump ", "--dump-filter", "--format", "--profile-out", "stixelnext"})
    EXPECT_NE(all.find(s), std::string::npos) << s;
}

}  // namespace

// The engine's dump of ConvNeXt-Tiny at a small input against direct computations: a
// ConvNeXt holding only the first k stages of the same weights is an independent
// forward whose output must be the dump's stage tensor features.(2k-1), bitwise, in
// NCHW; the last tensor is the model's own output.
namespace {

struct CollectingSink : nn::DumpSink {
  std::vector<std::string> order;
  std::map<std::string, std::vector<float>> data;
  std::map<std::string, std::vector<std::int64_t>> shapes;
  bool wants(const std::string&) const override { return true; }
  void tensor(const std::string& name, const std::vector<std::int64_t>& shape, const float* d,
              const std::string&) override {
    std::size_t n = 1;
    for (auto s : shape) n *= static_cast<std::size_t>(s);
    order.push_back(name);
    data[name].assign(d, d + n);
    shapes[name] = shape;
  }
};

std::vector<float> nchw_of(const nn::ConstTensorView& v) {
  std::vector<float> out(v.count());
  nn::nhwc_to_nchw(v.data, v.shape.n, v.shape.c, v.shape.h, v.shape.w, out.data());
  return out;
}

TEST(ConvNeXtDump, TinyStagesEqualTruncatedModelsBitwise) {
  const nn::ConvNeXtConfig tiny = nn::convnext_tiny_config();
  const auto full = weights::SafeTensors::from_bytes(
      nn::synthetic_weights(nn::convnext_tensor_specs(tiny, "features."), 11).bytes(), "synthetic tiny");
  std::vector<float> x(2 * 3 * 64 * 96);
  for (std::size_t i = 0; i < x.size(); ++i) x[i] = static_cast<float>((i * 7919) % 1000) / 500.0f - 1.0f;
  nn::ConvNeXt model(full);
  model.plan(2, 64, 96);
  CollectingSink sink;
  model.set_dump(&sink);
  const std::vector<float> y = nchw_of(model.forward(x.data()));
  // stem, 3 downsampling layers, 18 blocks x (block.0 .. block.4, the block), 4 stages, features
  ASSERT_EQ(sink.order.size(), 1u + 3 + 18 * 6 + 4 + 1);
  EXPECT_EQ(sink.order.back(), "features");
  EXPECT_TRUE(sink.data["features"] == y);
  EXPECT_EQ(sink.shapes["features"], (std::vector<std::int64_t>{2, 768, 2, 3}));
  for (int k = 1; k <= 3; ++k) {
    nn::ConvNeXtConfig part{std::vector<int>(tiny.dims.begin(), tiny.dims.begin() + k),
                            std::vector<int>(tiny.depths.begin(), tiny.depths.begin() + k)};
    weights::Writer w;
    for (const auto& s : nn::convnext_tensor_specs(part, "features.")) w.add_f32(s.name, s.shape, full.f32(s.name).data());
    const auto st = weights::SafeTensors::from_bytes(w.bytes(), "first stages");
    nn::ConvNeXt truncated(st);
    ASSERT_EQ(truncated.config().dims.size(), static_cast<std::size_t>(k));
    truncated.plan(2, 64, 96);
    const std::string stage = "features." + std::to_string(2 * k - 1);
    const std::string last_block = stage + "." + std::to_string(tiny.depths[k - 1] - 1);
    const std::vector<float> direct = nchw_of(truncated.forward(x.data()));
    EXPECT_TRUE(sink.data[stage] == direct) << stage;
    EXPECT_TRUE(sink.data[last_block] == direct) << last_block;
    const nn::Shape s = truncated.output_shape();
    EXPECT_EQ(sink.shapes[stage], (std::vector<std::int64_t>{s.n, s.c, s.h, s.w})) << stage;
  }
  // Dumping changes nothing: the same model without the sink gives the same bits.
  model.set_dump(nullptr);
  EXPECT_TRUE(nchw_of(model.forward(x.data())) == y);
}

}  // namespace
