// Writes the seed corpora for the fuzz harnesses, made by the project's own writers
// (weights::Writer, stixel::encode_stx1, shle::labelme_json, anchor_spec) plus a few
// hand-built PFM/DAT/PNG/JPEG headers:
//   fuzz_seeds OUT_DIR     -> OUT_DIR/<target>/seed_NN for every target
// The small text seeds committed in tests/fuzz/corpus/<target>/ are copied beside
// these by scripts/fuzz.
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "shle/labelme.h"
#include "stixel/anchors.h"
#include "stixel/stx1.h"
#include "weights/safetensors.h"

namespace fs = std::filesystem;

namespace {

fs::path g_out;

void put(const std::string& target, const std::vector<std::uint8_t>& bytes) {
  fs::path dir = g_out / target;
  fs::create_directories(dir);
  int n = 0;
  while (fs::exists(dir / ("seed_" + std::to_string(n)))) ++n;
  std::ofstream f(dir / ("seed_" + std::to_string(n)), std::ios::binary);
  f.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!f) {
    std::fprintf(stderr, "fuzz_seeds: cannot write %s\n", (dir / ("seed_" + std::to_string(n))).c_str());
    std::exit(1);
  }
}

void put(const std::string& target, const std::string& text) {
  put(target, std::vector<std::uint8_t>(text.begin(), text.end()));
}

std::vector<std::uint8_t> cat(std::vector<std::uint8_t> a, const std::vector<std::uint8_t>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

void safetensors_seeds() {
  {
    weights::Writer w;
    float f[6] = {1, -2, 0.5f, 3, 4, 5};
    w.add_f32("stem.weight", {2, 3}, f);
    std::int64_t i[2] = {7, -1};
    w.add_i64("steps", {2}, i);
    w.set_metadata("anchors", "tangent:4,66,64");
    put("safetensors", w.bytes());
  }
  {
    weights::Writer w;
    std::uint16_t h[4] = {0x3c00, 0x7c00, 0x0001, 0xfe00};
    w.add("h", weights::DType::F16, {4}, h);
    w.add("b", weights::DType::BF16, {2, 2}, h);
    std::uint8_t u[3] = {1, 2, 3};
    w.add("u", weights::DType::U8, {3}, u);
    w.add("flag", weights::DType::BOOL, {}, u);
    std::int32_t i32[1] = {-5};
    w.add("i32", weights::DType::I32, {1, 1}, i32);
    double d[1] = {2.5};
    w.add("d", weights::DType::F64, {1}, d);
    put("safetensors", w.bytes());
  }
  {
    // The smallest file: an empty header object, no data.
    std::string header = "{}";
    std::vector<std::uint8_t> b(8, 0);
    b[0] = static_cast<std::uint8_t>(header.size());
    b.insert(b.end(), header.begin(), header.end());
    put("safetensors", b);
  }
}

void stx1_seeds() {
  stixel::StixelWorld w;
  put("stx1", stixel::encode_stx1(w));
  stixel::Stixel s;
  s.u = 8; s.vT = 100; s.vB = 180; s.d = 12.5f; s.label = 3; s.width = 8; s.confidence = 0.9f; s.idx = 1;
  w.stixels.push_back(s);
  s.u = -4; s.cluster = -1; s.d = -0.0f;
  w.stixels.push_back(s);
  w.context.name = "frame_0001";
  w.context.clusters = 2;
  w.context.calibration.K = {2000, 0, 640, 0, 2000, 360, 0, 0, 1};
  w.context.calibration.T = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  w.context.calibration.distortion_model = stixel::kModelPlumbBob;
  w.context.calibration.D = {0.1f, 0, 0, 0, 0};
  w.context.calibration.reference = "Vehicle2Camera";
  w.context.calibration.img_name = "frame_0001.png";
  w.context.calibration.width = 1280;
  w.context.calibration.height = 720;
  w.context.calibration.channels = 3;
  w.has_context = true;
  put("stx1", stixel::encode_stx1(w));
  w.image = {0x89, 'P', 'N', 'G', 0x0d, 0x0a, 0x1a, 0x0a};
  put("stx1", stixel::encode_stx1(w));
}

std::vector<std::uint8_t> le32(std::int32_t v) {
  std::vector<std::uint8_t> b(4);
  std::memcpy(b.data(), &v, 4);
  return b;
}

void disparity_seeds() {
  // PFM (selector byte 0 = even): 3x2, little-endian, one NaN.
  for (const char* scale : {"-1.0", "1.0"}) {
    std::string head = std::string("Pf\n3 2\n") + scale + "\n";
    std::vector<std::uint8_t> b = {0};
    b.insert(b.end(), head.begin(), head.end());
    float v[6] = {1.5f, 0, 32, -1, 7, __builtin_nanf("")};
    if (scale[0] != '-')  // big-endian samples
      for (float& x : v) {
        std::uint32_t u;
        std::memcpy(&u, &x, 4);
        u = __builtin_bswap32(u);
        std::memcpy(&x, &u, 4);
      }
    const auto* p = reinterpret_cast<const std::uint8_t*>(v);
    b.insert(b.end(), p, p + sizeof v);
    put("disparity", b);
  }
  // DAT (selector odd): width, height, fraction bits, then width*height uint16.
  std::vector<std::uint8_t> b = {1};
  b = cat(b, le32(4));
  b = cat(b, le32(2));
  b.push_back(5);
  for (int i = 0; i < 8; ++i) {
    b.push_back(static_cast<std::uint8_t>(i * 37));
    b.push_back(static_cast<std::uint8_t>(i));
  }
  put("disparity", b);
}

void labelme_seeds() {
  std::vector<shle::Box> boxes(2);
  boxes[0] = {10, 20, 110, 60};
  boxes[1] = {500.5, 100, 520.25, 300};
  put("labelme", shle::labelme_json("frame_0001.png", 1280, 720, boxes));
  put("labelme", shle::labelme_json("empty.png", 640, 480, {}));
  put("json", shle::labelme_json("frame_0001.png", 1280, 720, boxes));
}

void anchors_seeds() {
  put("anchors", stixel::anchor_spec(stixel::tangent_anchors()));
  put("anchors", stixel::anchor_spec(stixel::linear_anchors(5, 69, 64)));
  put("anchors", std::string("tangent"));
  put("anchors", stixel::anchor_spec(stixel::tangent_anchors(1.5, 80.25, 3)));
}

void image_header_seeds() {
  // PNG signature + IHDR (13 bytes: 640x480, 8-bit RGB) + CRC.
  std::vector<std::uint8_t> png = {0x89, 'P', 'N', 'G', 0x0d, 0x0a, 0x1a, 0x0a, 0, 0, 0, 13, 'I', 'H', 'D', 'R',
                                   0, 0, 2, 0x80, 0, 0, 1, 0xe0, 8, 2, 0, 0, 0, 0x2b, 0x1a, 0x0e, 0x0b};
  put("image_header", png);
  // JPEG: SOI, APP0 (JFIF), SOF0 (8 bit, 720x1280, 3 components), EOI.
  std::vector<std::uint8_t> jpg = {0xff, 0xd8, 0xff, 0xe0, 0, 16, 'J', 'F', 'I', 'F', 0, 1, 1, 0, 0, 1, 0, 1, 0, 0,
                                   0xff, 0xc0, 0, 17, 8, 0x02, 0xd0, 0x05, 0x00, 3, 1, 0x22, 0, 2, 0x11, 1, 3,
                                   0x11, 1, 0xff, 0xd9};
  put("image_header", jpg);
  // Progressive JPEG (SOF2) after a fill byte.
  std::vector<std::uint8_t> prog = {0xff, 0xd8, 0xff, 0xff, 0xc2, 0, 11, 8, 0, 16, 0, 32, 1, 1, 0x11, 0};
  put("image_header", prog);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2 || std::strcmp(argv[1], "--help") == 0) {
    std::fprintf(stderr, "usage: fuzz_seeds OUT_DIR   (writes OUT_DIR/<target>/seed_N)\n");
    return argc == 2 ? 0 : 2;
  }
  g_out = argv[1];
  safetensors_seeds();
  stx1_seeds();
  disparity_seeds();
  labelme_seeds();
  anchors_seeds();
  image_header_seeds();
  return 0;
}
