// roadnn_session_set_dump: the intermediate tensors of a run, under PyTorch's module
// names, in network order and PyTorch's layout; off by default and when reset to NULL.
#include <algorithm>
#include <map>

#include "tests/api/api_util.h"

namespace {

using namespace apitest;

struct Dumped {
  std::vector<std::string> order;
  std::map<std::string, std::vector<std::int64_t>> shapes;
  std::map<std::string, std::vector<float>> data;
  std::map<std::string, std::string> covers;
};

void collect(const char* name, const std::int64_t* shape, int rank, const float* data, const char* covers, void* user) {
  auto& d = *static_cast<Dumped*>(user);
  std::size_t count = 1;
  for (int i = 0; i < rank; ++i) count *= static_cast<std::size_t>(shape[i]);
  d.order.push_back(name);
  d.shapes[name].assign(shape, shape + rank);
  d.data[name].assign(data, data + count);
  d.covers[name] = covers;
}

bool has(const Dumped& d, const std::string& name) { return d.shapes.count(name) > 0; }

TEST(ApiDump, NullSessionIsAnError) {
  Dumped d;
  EXPECT_API_ERROR(roadnn_session_set_dump(nullptr, collect, &d), ROADNN_ERROR_INVALID_ARGUMENT, "session is null");
}

TEST(ApiDump, ConvNeXtBlocksInNetworkOrderAndTheLastIsTheOutput) {
  ModelPtr m = load_convnext();
  SessionPtr s = convnext_session(m.get(), 2);
  const auto x = convnext_input(3);
  std::int64_t shape[4];
  ASSERT_EQ(ROADNN_OK, roadnn_convnext_output_shape(s.get(), shape));
  std::vector<float> y(static_cast<std::size_t>(shape[0] * shape[1] * shape[2] * shape[3]));
  Dumped d;
  ASSERT_EQ(ROADNN_OK, roadnn_session_set_dump(s.get(), collect, &d));
  ASSERT_EQ(ROADNN_OK, roadnn_convnext_run(s.get(), x.data(), x.size(), y.data(), y.size())) << roadnn_last_error();
  // small_convnext(): 4 stages of one block each.
  std::vector<std::string> want = {"features.0"};
  for (int stage = 1; stage <= 7; stage += 2) {
    if (stage > 1) want.push_back("features." + std::to_string(stage - 1));
    const std::string b = "features." + std::to_string(stage) + ".0";
    for (int layer = 0; layer <= 4; ++layer) want.push_back(b + ".block." + std::to_string(layer));
    want.push_back(b);
    want.push_back("features." + std::to_string(stage));
  }
  want.push_back("features");
  EXPECT_EQ(d.order, want);
  EXPECT_EQ(d.shapes["features.0"], (std::vector<std::int64_t>{1, 8, kConvH / 4, kConvW / 4}));
  EXPECT_EQ(d.shapes["features"], (std::vector<std::int64_t>{shape[0], shape[1], shape[2], shape[3]}));
  // NCHW, bitwise the run's output.
  EXPECT_TRUE(d.data["features"] == y);
  EXPECT_TRUE(d.data["features.7"] == d.data["features.7.0"]);
  EXPECT_NE(d.covers["features.1.0"].find("features.1.0.block.5"), std::string::npos) << d.covers["features.1.0"];
  EXPECT_EQ(d.shapes["features.1.0.block.4"], (std::vector<std::int64_t>{1, kConvH / 4, kConvW / 4, 32}));
  EXPECT_EQ(d.covers["features.1.0.block.0"], "");
  // Dumping changes nothing in the result; off again, the callback is not called.
  std::vector<float> y2(y.size());
  ASSERT_EQ(ROADNN_OK, roadnn_session_set_dump(s.get(), nullptr, nullptr));
  ASSERT_EQ(ROADNN_OK, roadnn_convnext_run(s.get(), x.data(), x.size(), y2.data(), y2.size()));
  EXPECT_TRUE(y == y2);
  EXPECT_EQ(d.order.size(), want.size());
}

TEST(ApiDump, OffByDefault) {
  ModelPtr m = load_convnext();
  SessionPtr s = convnext_session(m.get(), 1);
  // A session never given a callback runs as before (nothing to observe but the
  // result, which equals a dumping session's).
  SessionPtr t = convnext_session(m.get(), 1);
  Dumped d;
  ASSERT_EQ(ROADNN_OK, roadnn_session_set_dump(t.get(), collect, &d));
  const auto x = convnext_input(4);
  std::vector<float> a(28 * (kConvH / 32) * (kConvW / 32)), b(a.size());
  ASSERT_EQ(ROADNN_OK, roadnn_convnext_run(s.get(), x.data(), x.size(), a.data(), a.size()));
  ASSERT_EQ(ROADNN_OK, roadnn_convnext_run(t.get(), x.data(), x.size(), b.data(), b.size()));
  EXPECT_TRUE(a == b);
  EXPECT_FALSE(d.order.empty());
}

TEST(ApiDump, StixelNExTBackboneAndHead) {
  ModelPtr m = load_stixel();
  SessionPtr s = session(m.get(), 2);
  const auto px = pixels(kStixelW, kStixelH, 5);
  const roadnn_image im = image_of(px, kStixelW, kStixelH);
  Dumped d;
  ASSERT_EQ(ROADNN_OK, roadnn_session_set_dump(s.get(), collect, &d));
  roadnn_stixel_world w;
  ASSERT_EQ(ROADNN_OK, roadnn_stixel_run(s.get(), &im, nullptr, nullptr, &w)) << roadnn_last_error();
  for (const char* n : {"features.0", "features", "avgpool", "classifier.local_mixing.depthwise",
                        "classifier.shared_reduce", "classifier.up.0", "classifier.up", "classifier"})
    EXPECT_TRUE(has(d, n)) << n;
  EXPECT_EQ(d.order.back(), "classifier");
  EXPECT_EQ(d.shapes["classifier"], (std::vector<std::int64_t>{1, 4, 64, kStixelW / 8}));
  EXPECT_EQ(d.shapes["classifier.up"], (std::vector<std::int64_t>{1, 256, 1, kStixelW / 8}));
  EXPECT_NE(d.covers["classifier"].find("classifier.probability_head"), std::string::npos);
}

TEST(ApiDump, DetectorPyramidProposalsAndHeads) {
  SessionPtr s = session(shared_detector(), 2, kDetH, kDetW);
  const auto px = pixels(kDetW, kDetH, 6);
  const roadnn_image im = image_of(px, kDetW, kDetH);
  Dumped d;
  ASSERT_EQ(ROADNN_OK, roadnn_session_set_dump(s.get(), collect, &d));
  roadnn_detections dets;
  ASSERT_EQ(ROADNN_OK, roadnn_detect(s.get(), &im, &dets)) << roadnn_last_error();
  for (const char* n : {"transform[0]", "backbone.body[0]", "backbone.body[1]", "backbone.fpn[0]", "backbone.fpn[pool]",
                        "backbone[pool]", "rpn.head.conv", "rpn.head.cls_logits#2", "rpn.head[1][2]", "rpn[0][0]"})
    EXPECT_TRUE(has(d, n)) << n;
  const auto& p = d.shapes["rpn[0][0]"];
  ASSERT_EQ(p.size(), 2u);
  EXPECT_EQ(p[1], 4);
  if (p[0] > 0) {
    EXPECT_EQ(d.shapes["roi_heads.box_roi_pool"], (std::vector<std::int64_t>{p[0], 256, 7, 7}));
    EXPECT_EQ(d.shapes["roi_heads.box_head"], (std::vector<std::int64_t>{p[0], 1024}));
    EXPECT_EQ(d.shapes["roi_heads.box_predictor.cls_score"], (std::vector<std::int64_t>{p[0], kDetClasses}));
  }
  // Network order: the pyramid before the RPN, the RPN before the RoI heads.
  auto at = [&](const std::string& n) { return std::find(d.order.begin(), d.order.end(), n) - d.order.begin(); };
  EXPECT_LT(at("backbone.fpn[pool]"), at("rpn.head.conv"));
  EXPECT_LT(at("rpn.head.conv"), at("rpn[0][0]"));
}

}  // namespace
