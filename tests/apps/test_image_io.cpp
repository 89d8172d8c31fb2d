// image_io: decoding, 16-bit PNGs, damaged files and atomic writes.
#include "apps/common/image_io.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STBI_WRITE_NO_STDIO
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#include "stb_image_write.h"
#pragma GCC diagnostic pop

namespace fs = std::filesystem;
using Bytes = std::vector<std::uint8_t>;

namespace {

// A fresh folder per test, so ctest may run the cases in parallel.
std::string test_dir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  fs::path dir = fs::path(ROADNN_BINARY_DIR) / "test_tmp" / "apps" /
                 (std::string(info->test_suite_name()) + "." + info->name());
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

void write_raw(const std::string& path, const Bytes& b) {
  std::ofstream f(path, std::ios::binary);
  f.write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
}

Bytes read_raw(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(f), {});
}

std::vector<std::string> folder_entries(const std::string& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  return names;
}

Bytes pattern(int w, int h, int c) {
  Bytes px(static_cast<std::size_t>(w) * h * c);
  for (std::size_t i = 0; i < px.size(); ++i) px[i] = static_cast<std::uint8_t>((i * 37 + i / 7) & 0xFF);
  return px;
}

// Expects `fn` to throw imageio::Error whose message starts with "path: " and
// contains `needle`.
template <class Fn>
void expect_error(Fn fn, const std::string& path, const std::string& needle) {
  try {
    fn();
    ADD_FAILURE() << "no error for " << path << " (expected '" << needle << "')";
  } catch (const imageio::Error& e) {
    std::string msg = e.what();
    EXPECT_EQ(msg.rfind(path + ": ", 0), 0u) << msg;
    EXPECT_NE(msg.find(needle), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  }
}

// --- a minimal PNG writer for 16-bit files (stb_image_write only writes 8-bit) ---
std::uint32_t crc32_bitwise(const std::uint8_t* p, std::size_t n) {
  std::uint32_t c = 0xFFFFFFFFu;
  for (std::size_t i = 0; i < n; ++i) {
    c ^= p[i];
    for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
  }
  return c ^ 0xFFFFFFFFu;
}

void put_be32(Bytes& b, std::uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) b.push_back(static_cast<std::uint8_t>(v >> s));
}

void add_chunk(Bytes& png, const char* type, const Bytes& data) {
  put_be32(png, static_cast<std::uint32_t>(data.size()));
  Bytes body(type, type + 4);
  body.insert(body.end(), data.begin(), data.end());
  png.insert(png.end(), body.begin(), body.end());
  put_be32(png, crc32_bitwise(body.data(), body.size()));
}

// Gray (color type 0) or RGB (2), 16 bits per sample, filter 0, zlib stored blocks.
Bytes png16(int w, int h, int channels, const std::vector<std::uint16_t>& samples) {
  Bytes raw;
  for (int y = 0; y < h; ++y) {
    raw.push_back(0);
    for (int i = 0; i < w * channels; ++i) {
      std::uint16_t s = samples[static_cast<std::size_t>(y) * w * channels + i];
      raw.push_back(static_cast<std::uint8_t>(s >> 8));
      raw.push_back(static_cast<std::uint8_t>(s & 0xFF));
    }
  }
  Bytes z = {0x78, 0x01};
  std::size_t pos = 0;
  do {
    std::size_t n = std::min<std::size_t>(65535, raw.size() - pos);
    bool last = pos + n == raw.size();
    z.push_back(last ? 1 : 0);
    z.push_back(n & 0xFF);
    z.push_back((n >> 8) & 0xFF);
    z.push_back(~n & 0xFF);
    z.push_back((~n >> 8) & 0xFF);
    z.insert(z.end(), raw.begin() + pos, raw.begin() + pos + n);
    pos += n;
  } while (pos < raw.size());
  std::uint32_t a = 1, b = 0;
  for (auto v : raw) {
    a = (a + v) % 65521;
    b = (b + a) % 65521;
  }
  put_be32(z, (b << 16) | a);
  Bytes png = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
  Bytes ihdr;
  put_be32(ihdr, w);
  put_be32(ihdr, h);
  ihdr.push_back(16);
  ihdr.push_back(channels == 1 ? 0 : 2);
  ihdr.push_back(0);
  ihdr.push_back(0);
  ihdr.push_back(0);
  add_chunk(png, "IHDR", ihdr);
  add_chunk(png, "IDAT", z);
  add_chunk(png, "IEND", {});
  return png;
}

Bytes stb_encode(bool jpeg, int w, int h, int c, const Bytes& px) {
  Bytes out;
  auto append = [](void* ctx, void* data, int size) {
    auto* v = static_cast<Bytes*>(ctx);
    v->insert(v->end(), static_cast<std::uint8_t*>(data), static_cast<std::uint8_t*>(data) + size);
  };
  int ok = jpeg ? stbi_write_jpg_to_func(append, &out, w, h, c, px.data(), 95)
                : stbi_write_bmp_to_func(append, &out, w, h, c, px.data());
  EXPECT_TRUE(ok);
  return out;
}

}  // namespace

TEST(ImageIo, PngRoundTripEveryChannelCount) {
  std::string dir = test_dir();
  for (int c = 1; c <= 4; ++c) {
    const int w = 37, h = 23;  // odd sizes: no row-alignment luck
    Bytes px = pattern(w, h, c);
    std::string path = dir + "/c" + std::to_string(c) + ".png";
    imageio::save_png(path, px.data(), w, h, c);
    imageio::Image img = imageio::load(path);
    EXPECT_EQ(img.width, w);
    EXPECT_EQ(img.height, h);
    EXPECT_EQ(img.channels, c);
    EXPECT_EQ(img.bit_depth, 8);
    EXPECT_TRUE(img.u16.empty());
    EXPECT_EQ(img.u8, px) << "channels " << c;
  }
}

TEST(ImageIo, EncodePngToMemoryMatchesSavedFile) {
  std::string dir = test_dir();
  Bytes px = pattern(16, 9, 3);
  Bytes mem = imageio::encode_png(px.data(), 16, 9, 3);
  ASSERT_GT(mem.size(), 8u);
  EXPECT_EQ(mem[0], 0x89);
  EXPECT_EQ(mem[1], 'P');
  imageio::save_png(dir + "/a.png", px.data(), 16, 9, 3);
  EXPECT_EQ(read_raw(dir + "/a.png"), mem);
}

TEST(ImageIo, ChannelConversionOnLoad) {
  std::string dir = test_dir();
  Bytes gray = {0, 100, 200, 255};
  imageio::save_png(dir + "/g.png", gray.data(), 2, 2, 1);
  imageio::Image rgb = imageio::load(dir + "/g.png", 3);
  ASSERT_EQ(rgb.channels, 3);
  ASSERT_EQ(rgb.u8.size(), 12u);
  for (int i = 0; i < 4; ++i)
    for (int k = 0; k < 3; ++k) EXPECT_EQ(rgb.u8[i * 3 + k], gray[i]);
  imageio::Image rgba = imageio::load(dir + "/g.png", 4);
  ASSERT_EQ(rgba.channels, 4);
  EXPECT_EQ(rgba.u8[3], 255);
}

TEST(ImageIo, SixteenBitPng) {
  std::string dir = test_dir();
  const int w = 5, h = 3;
  std::vector<std::uint16_t> s(w * h);
  for (int i = 0; i < w * h; ++i) s[i] = static_cast<std::uint16_t>(i * 4099 + 17);
  write_raw(dir + "/d.png", png16(w, h, 1, s));

  imageio::Image img = imageio::load(dir + "/d.png", 0, true);
  EXPECT_EQ(img.bit_depth, 16);
  EXPECT_EQ(img.channels, 1);
  EXPECT_TRUE(img.u8.empty());
  EXPECT_EQ(img.u16, s);

  // Without keep_16bit the samples are reduced to their high byte.
  imageio::Image img8 = imageio::load(dir + "/d.png");
  EXPECT_EQ(img8.bit_depth, 8);
  ASSERT_EQ(img8.u8.size(), s.size());
  for (std::size_t i = 0; i < s.size(); ++i) EXPECT_EQ(img8.u8[i], s[i] >> 8);

  // An 8-bit file stays 8-bit even when 16 bits are accepted.
  Bytes px = pattern(4, 4, 3);
  imageio::save_png(dir + "/e.png", px.data(), 4, 4, 3);
  imageio::Image e = imageio::load(dir + "/e.png", 0, true);
  EXPECT_EQ(e.bit_depth, 8);
  EXPECT_EQ(e.u8, px);
}

TEST(ImageIo, SixteenBitRgbWithChannelConversion) {
  std::string dir = test_dir();
  std::vector<std::uint16_t> s = {1000, 2000, 3000, 60000, 50000, 40000};
  write_raw(dir + "/rgb16.png", png16(2, 1, 3, s));
  imageio::Image img = imageio::load(dir + "/rgb16.png", 4, true);
  ASSERT_EQ(img.channels, 4);
  ASSERT_EQ(img.u16.size(), 8u);
  EXPECT_EQ(img.u16[0], 1000);
  EXPECT_EQ(img.u16[5], 50000);
  EXPECT_EQ(img.u16[3], 65535);  // opaque alpha at full 16-bit scale
}

TEST(ImageIo, JpegAndBmpDecode) {
  std::string dir = test_dir();
  const int w = 24, h = 16;
  Bytes px(w * h * 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      px[(y * w + x) * 3 + 0] = 200;
      px[(y * w + x) * 3 + 1] = 40;
      px[(y * w + x) * 3 + 2] = 90;
    }
  write_raw(dir + "/a.jpg", stb_encode(true, w, h, 3, px));
  imageio::Image j = imageio::load(dir + "/a.jpg");
  EXPECT_EQ(j.width, w);
  EXPECT_EQ(j.height, h);
  EXPECT_EQ(j.channels, 3);
  for (std::size_t i = 0; i < px.size(); ++i) EXPECT_NEAR(j.u8[i], px[i], 4) << i;

  Bytes px4 = pattern(7, 5, 3);
  write_raw(dir + "/a.bmp", stb_encode(false, 7, 5, 3, px4));
  imageio::Image b = imageio::load(dir + "/a.bmp");
  EXPECT_EQ(b.width, 7);
  EXPECT_EQ(b.u8, px4);
}

TEST(ImageIo, TruncatedPngAtEveryLengthIsAnError) {
  std::string dir = test_dir();
  Bytes px = pattern(20, 10, 3);
  Bytes png = imageio::encode_png(px.data(), 20, 10, 3);
  for (std::size_t n = 1; n < png.size(); ++n) {
    std::string path = dir + "/t.png";
    write_raw(path, Bytes(png.begin(), png.begin() + n));
    expect_error([&] { imageio::load(path); }, path, n < 8 ? "unsupported" : "truncated PNG");
  }
}

TEST(ImageIo, CorruptPngIsAnError) {
  std::string dir = test_dir();
  Bytes px = pattern(20, 10, 3);
  Bytes png = imageio::encode_png(px.data(), 20, 10, 3);
  std::string path = dir + "/c.png";

  Bytes flipped = png;
  flipped[png.size() / 2] ^= 0x40;  // inside IDAT: its CRC no longer matches
  write_raw(path, flipped);
  expect_error([&] { imageio::load(path); }, path, "CRC mismatch in chunk 'IDAT'");

  // Damaged compressed data with a recomputed (valid) CRC reaches the decoder.
  std::vector<std::uint16_t> samples(16, 5);
  Bytes p16 = png16(4, 4, 1, samples);
  std::size_t idat = 8 + 25;  // after the signature and the IHDR chunk
  std::uint32_t len = (p16[idat] << 24) | (p16[idat + 1] << 16) | (p16[idat + 2] << 8) | p16[idat + 3];
  p16[idat + 8 + 2] = 0x07;  // deflate block type 3: invalid
  std::uint32_t crc = crc32_bitwise(&p16[idat + 4], len + 4);
  for (int k = 0; k < 4; ++k) p16[idat + 8 + len + k] = static_cast<std::uint8_t>(crc >> (24 - 8 * k));
  write_raw(path, p16);
  expect_error([&] { imageio::load(path, 0, true); }, path, "cannot decode PNG");
}

TEST(ImageIo, TruncatedJpegAndBmpAreErrors) {
  std::string dir = test_dir();
  Bytes px = pattern(32, 32, 3);
  Bytes jpg = stb_encode(true, 32, 32, 3, px);
  std::string path = dir + "/t.jpg";
  for (std::size_t n : {3ul, 10ul, jpg.size() / 2, jpg.size() - 2, jpg.size() - 1}) {
    write_raw(path, Bytes(jpg.begin(), jpg.begin() + n));
    expect_error([&] { imageio::load(path); }, path, "JPEG");
  }
  Bytes bmp = stb_encode(false, 9, 7, 3, pattern(9, 7, 3));
  path = dir + "/t.bmp";
  for (std::size_t n : {2ul, 20ul, 60ul, bmp.size() - 1}) {
    write_raw(path, Bytes(bmp.begin(), bmp.begin() + n));
    expect_error([&] { imageio::load(path); }, path, "BMP");
  }
}

TEST(ImageIo, UnreadableOrUnsupportedFiles) {
  std::string dir = test_dir();
  expect_error([&] { imageio::load(dir + "/missing.png"); }, dir + "/missing.png", "cannot open");
  expect_error([&] { imageio::load(dir); }, dir, "not a regular file");
  write_raw(dir + "/empty.png", {});
  expect_error([&] { imageio::load(dir + "/empty.png"); }, dir + "/empty.png", "empty file");
  write_raw(dir + "/text.png", Bytes{'h', 'e', 'l', 'l', 'o', '\n'});
  expect_error([&] { imageio::load(dir + "/text.png"); }, dir + "/text.png",
               "unsupported image format");
  Bytes gif = {'G', 'I', 'F', '8', '9', 'a', 1, 0, 1, 0, 0, 0, 0};
  write_raw(dir + "/a.gif", gif);
  expect_error([&] { imageio::load(dir + "/a.gif"); }, dir + "/a.gif", "unsupported image format");
  Bytes px = pattern(2, 2, 3);
  imageio::save_png(dir + "/ok.png", px.data(), 2, 2, 3);
  expect_error([&] { imageio::load(dir + "/ok.png", 7); }, dir + "/ok.png", "channel count");
}

TEST(ImageIo, FailedWritesLeaveNothingBehind) {
  std::string dir = test_dir();
  Bytes px = pattern(4, 4, 3);
  std::string bad = dir + "/no_such_folder/x.png";
  expect_error([&] { imageio::save_png(bad, px.data(), 4, 4, 3); }, bad, "cannot create");
  // The target is an existing folder: rename fails, the temporary is removed.
  fs::create_directories(dir + "/taken");
  fs::create_directories(dir + "/taken/sub");
  expect_error([&] { imageio::save_png(dir + "/taken", px.data(), 4, 4, 3); }, dir + "/taken",
               "cannot write");
  expect_error([&] { imageio::save_png(dir + "/z.png", px.data(), 0, 4, 3); }, dir + "/z.png",
               "invalid image shape");
  expect_error([&] { imageio::save_png(dir + "/z.png", px.data(), 4, 4, 5); }, dir + "/z.png",
               "invalid image shape");
  EXPECT_EQ(folder_entries(dir), std::vector<std::string>{"taken"});
  EXPECT_THROW(imageio::encode_png(nullptr, 4, 4, 3), imageio::Error);
}
