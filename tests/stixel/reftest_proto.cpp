// .stx1 compatibility with the real protobuf library (python3-protobuf, schema
// compiled with protoc at test time): we decode and re-encode files protobuf
// wrote, and protobuf decodes and re-encodes files we wrote, byte for byte.
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

#include "stixel/anchors.h"
#include "stixel/clustering.h"
#include "stixel/extract.h"
#include "stixel/stx1.h"
#include "stixel/text_formats.h"
#include "tests/stixel/reftest_util.h"

namespace {

void write_file(const std::string& path, const void* data, std::size_t n) {
  std::ofstream f(path, std::ios::binary);
  f.write(static_cast<const char*>(data), static_cast<std::streamsize>(n));
  ASSERT_TRUE(f.good()) << path;
}

template <class T, class F>
void expect_field(const std::vector<stixel::Stixel>& s, const std::vector<T>& ref, F get, const char* name) {
  ASSERT_EQ(s.size(), ref.size()) << name;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    const T v = get(s[i]);
    if (std::memcmp(&v, &ref[i], sizeof(T)) != 0) {  // bitwise: NaN and -0.0 included
      ADD_FAILURE() << name << " of stixel " << i << ": ours " << v << ", protobuf " << ref[i];
      return;
    }
  }
}

std::vector<std::int32_t> ints(const weights::SafeTensors& st, const std::string& name) {
  std::vector<std::int32_t> out;
  for (std::int64_t v : st.i64(name)) out.push_back(static_cast<std::int32_t>(v));
  return out;
}

// Field-by-field comparison of our world with protobuf's dump of a message.
void expect_matches_dump(const stixel::StixelWorld& w, const weights::SafeTensors& st) {
  using S = stixel::Stixel;
  EXPECT_EQ(std::to_string(w.stixels.size()), stxref::meta(st, "stixels"));
  expect_field(w.stixels, ints(st, "u"), [](const S& s) { return s.u; }, "u");
  expect_field(w.stixels, ints(st, "vT"), [](const S& s) { return s.vT; }, "vT");
  expect_field(w.stixels, ints(st, "vB"), [](const S& s) { return s.vB; }, "vB");
  expect_field(w.stixels, st.f32("d"), [](const S& s) { return s.d; }, "d");
  expect_field(w.stixels, ints(st, "label"), [](const S& s) { return s.label; }, "label");
  expect_field(w.stixels, ints(st, "width"), [](const S& s) { return s.width; }, "width");
  expect_field(w.stixels, st.f32("confidence"), [](const S& s) { return s.confidence; }, "confidence");
  expect_field(w.stixels, ints(st, "idx"), [](const S& s) { return s.idx; }, "idx");
  expect_field(w.stixels, ints(st, "cluster"), [](const S& s) { return s.cluster; }, "cluster");
  const stixel::CameraInfo& c = w.context.calibration;
  EXPECT_EQ(c.K, st.f32("calibration_K"));
  EXPECT_EQ(c.T, st.f32("calibration_T"));
  EXPECT_EQ(c.R, st.f32("calibration_R"));
  EXPECT_EQ(c.D, st.f32("calibration_D"));
  EXPECT_EQ(w.image, stxref::u8(st, "image"));
  EXPECT_EQ(w.context.name, stxref::meta(st, "name"));
  EXPECT_EQ(std::to_string(w.context.clusters), stxref::meta(st, "clusters"));
  EXPECT_EQ(std::to_string(c.distortion_model), stxref::meta(st, "distortion_model"));
  EXPECT_EQ(c.reference, stxref::meta(st, "reference"));
  EXPECT_EQ(c.img_name, stxref::meta(st, "img_name"));
  EXPECT_EQ(std::to_string(c.width), stxref::meta(st, "width"));
  EXPECT_EQ(std::to_string(c.height), stxref::meta(st, "height"));
  EXPECT_EQ(std::to_string(c.channels), stxref::meta(st, "channels"));
}

void check_protobuf_file(const std::string& name, bool has_context, bool has_calibration) {
  SCOPED_TRACE(name);
  const std::string path = stxref::ref_path("stixel_proto_" + name + ".stx1");
  const auto dump = stxref::load("stixel_proto_" + name + ".safetensors");
  const stixel::StixelWorld w = stixel::read_stx1(path);
  expect_matches_dump(w, dump);
  EXPECT_EQ(w.has_context, has_context);
  EXPECT_EQ(w.context.has_calibration, has_calibration);
  EXPECT_EQ(stxref::meta(dump, "has_context"), has_context ? "1" : "0");
  EXPECT_EQ(stxref::meta(dump, "has_calibration"), has_calibration ? "1" : "0");
  // Our encoder writes exactly protobuf's bytes (unknown fields are dropped).
  EXPECT_EQ(stixel::encode_stx1(w), stxref::u8(dump, "canonical"));
}

// Runs protobuf on a file we wrote; returns its dump.
weights::SafeTensors protobuf_decode(const stixel::StixelWorld& w, const std::string& name) {
  const std::string dir = std::string(ROADNN_BINARY_DIR) + "/test_tmp/stixel";
  std::filesystem::create_directories(dir);
  const std::string base = dir + "/" + name;
  const std::vector<std::uint8_t> bytes = stixel::encode_stx1(w);
  write_file(base + ".stx1", bytes.data(), bytes.size());
  stixel::JsonOptions jo;
  jo.include_image = true;
  const std::string json = stixel::to_json(w, jo);
  write_file(base + ".json", json.data(), json.size());
  std::remove((base + ".dump.safetensors").c_str());
  const std::string cmd = std::string(ROADNN_PYTHON) + " " + ROADNN_SOURCE_DIR +
                          "/tests/reference/stixel_proto_check.py --pb-dir " + ROADNN_REF_DIR +
                          "/stixel_pb --input " + base + ".stx1 --json " + base + ".json --dump " + base +
                          ".dump.safetensors";
  const int rc = std::system(cmd.c_str());
  EXPECT_EQ(rc, 0) << "protobuf rejected our file (see the message above): " << cmd;
  return stxref::load_path(base + ".dump.safetensors");
}

stixel::StixelWorld our_full_world() {
  stixel::StixelWorld w;
  std::mt19937 rng(17);
  for (int i = 0; i < 500; ++i) {
    stixel::Stixel s;
    s.u = static_cast<int>(rng() % 1920) - 5;
    s.vT = static_cast<int>(rng() % 1400) - 50;
    s.vB = static_cast<int>(rng() % 1400);
    s.d = (i % 7 == 0) ? 0.0f : std::ldexp(static_cast<float>(rng() % 100000), -10);
    s.label = static_cast<int>(rng() % 23);
    s.width = i % 5 ? 8 : 0;
    s.confidence = i % 11 == 0 ? -0.0f : static_cast<float>(rng() % 1000) / 999.0f;
    s.idx = i;
    s.cluster = static_cast<int>(rng() % 40) - 1;
    w.stixels.push_back(s);
  }
  w.stixels[3].d = INFINITY;
  w.stixels[4].vT = INT32_MIN;
  w.stixels[5].vB = INT32_MAX;
  w.image = {0xFF, 0xD8, 0xFF, 0xE0, 0, 16, 'J', 'F', 'I', 'F'};
  w.context.name = "caf\xc3\xa9 \xe6\x9d\xb1\xe4\xba\xac \xf0\x9f\x9a\x97";  // café 東京 🚗
  auto& c = w.context.calibration;
  c.K = {2081.253f, 0, 954.13f, 0, 2081.253f, 664.492f, 0, 0, 1};
  c.T = {1, 0, 0, -1.545f, 0, 1, 0, 0.05f, 0, 0, 1, -2.115f, 0, 0, 0, 1};
  c.R = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  c.D = {0.0449f, -0.354f, 0.0f, 0.0f, 0.0f};
  c.distortion_model = stixel::kModelPlumbBob;
  c.reference = "Vehicle2Camera";
  c.img_name = "a \"quoted\"\\name\n.png";
  c.width = 1920;
  c.height = 1280;
  c.channels = 3;
  w.context.clusters = 38;
  return w;
}

}  // namespace

TEST(ProtoRef, WeReadWhatProtobufWrites) {
  check_protobuf_file("full", true, true);
  check_protobuf_file("frame", true, true);
  check_protobuf_file("empty", false, false);
  check_protobuf_file("negative", true, true);
}

TEST(ProtoRef, UnknownFieldsAreSkipped) {
  const stixel::StixelWorld w = stixel::read_stx1(stxref::ref_path("stixel_proto_unknown.stx1"));
  const auto dump = stxref::load("stixel_proto_unknown.safetensors");
  expect_matches_dump(w, dump);
  ASSERT_EQ(w.stixels.size(), 4u);
  EXPECT_EQ(w.stixels[3].u, 5);
  EXPECT_EQ(stixel::encode_stx1(w), stxref::u8(dump, "canonical"));
}

TEST(ProtoRef, ProtobufReadsWhatWeWrite) {
  const stixel::StixelWorld w = our_full_world();
  expect_matches_dump(w, protobuf_decode(w, "full"));
}

TEST(ProtoRef, ProtobufReadsAFullExtractedFrame) {
  // A realistic file: all 15,360 candidates of a V4 prediction, clustered.
  std::mt19937 rng(23);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::vector<float> pred(4 * 64 * 240);
  for (float& v : pred) v = unit(rng);
  stixel::ExtractOptions o;
  o.threshold = 0.0;
  stixel::StixelWorld w = stixel::extract(pred.data(), 4, 64, 240, stixel::tangent_anchors(), o);
  w.context.name = "frame_000123";
  w.context.calibration.K = {2000.0f, 0, 960.0f, 0, 2000.0f, 640.0f, 0, 0, 1};
  w.context.calibration.T = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  w.context.calibration.width = 1920;
  w.context.calibration.height = 1280;
  stixel::cluster_stixels(w, stixel::Projection(w.context.calibration), {});
  expect_matches_dump(w, protobuf_decode(w, "frame"));
}

TEST(ProtoRef, ProtobufReadsEmptyAndDefaultOnlyWorlds) {
  expect_matches_dump(stixel::StixelWorld{}, protobuf_decode(stixel::StixelWorld{}, "empty"));
  stixel::StixelWorld w;
  w.stixels.resize(3);
  w.has_context = true;
  w.context.has_calibration = true;
  w.context.clusters = -1;
  const auto dump = protobuf_decode(w, "defaults");
  expect_matches_dump(w, dump);
  EXPECT_EQ(stxref::meta(dump, "has_calibration"), "1");
}
