// image_io: decoding, 16-bit PNGs, damaged and hostile files, limits, special files
// and atomic writes. The JPEG fixtures are written with libjpeg here, the BMPs by hand.
#include "apps/common/image_io.h"

#include <gtest/gtest.h>

#include "tests/apps/test_dir.h"
#include <sys/stat.h>
#include <sys/wait.h>
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <future>
#include <string>
#include <vector>

#include <jpeglib.h>

namespace fs = std::filesystem;
using Bytes = std::vector<std::uint8_t>;

namespace {

using appstest::test_dir;

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
    for (char ch : msg) EXPECT_FALSE(static_cast<unsigned char>(ch) < 32 || ch == 127) << "control character in: " << msg;
  }
}

// --- a minimal PNG writer for 16-bit files (encode_png only writes 8-bit) ---
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

// A JPEG written by libjpeg (the decoder's own library, so this checks our use of it).
Bytes jpeg_encode(int w, int h, int c, const Bytes& px, int quality = 95, bool progressive = false) {
  jpeg_compress_struct cinfo;
  jpeg_error_mgr err;
  cinfo.err = jpeg_std_error(&err);
  jpeg_create_compress(&cinfo);
  unsigned char* mem = nullptr;
  unsigned long size = 0;
  jpeg_mem_dest(&cinfo, &mem, &size);
  cinfo.image_width = w;
  cinfo.image_height = h;
  cinfo.input_components = c;
  cinfo.in_color_space = c == 1 ? JCS_GRAYSCALE : JCS_RGB;
  jpeg_set_defaults(&cinfo);
  jpeg_set_quality(&cinfo, quality, TRUE);
  if (progressive) jpeg_simple_progression(&cinfo);
  jpeg_start_compress(&cinfo, TRUE);
  while (cinfo.next_scanline < cinfo.image_height) {
    JSAMPROW row = const_cast<JSAMPROW>(&px[std::size_t(cinfo.next_scanline) * w * c]);
    jpeg_write_scanlines(&cinfo, &row, 1);
  }
  jpeg_finish_compress(&cinfo);
  Bytes out(mem, mem + size);
  jpeg_destroy_compress(&cinfo);
  std::free(mem);
  return out;
}

void put_le(Bytes& b, std::uint32_t v, int n) {
  for (int i = 0; i < n; ++i) b.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

// Uncompressed BMP, 24-bit (c = 3) or 32-bit BI_RGB (c = 4), bottom-up unless top_down.
Bytes bmp_encode(int w, int h, int c, const Bytes& px, bool top_down = false) {
  const std::uint32_t stride = ((w * c * 8 + 31) / 32) * 4;
  Bytes b = {'B', 'M'};
  put_le(b, 54 + stride * h, 4);
  put_le(b, 0, 4);
  put_le(b, 54, 4);
  put_le(b, 40, 4);
  put_le(b, w, 4);
  put_le(b, top_down ? std::uint32_t(-h) : std::uint32_t(h), 4);
  put_le(b, 1, 2);
  put_le(b, c * 8, 2);
  for (int i = 0; i < 6; ++i) put_le(b, 0, 4);
  for (int r = 0; r < h; ++r) {
    int y = top_down ? r : h - 1 - r;
    for (int x = 0; x < w; ++x) {
      const std::uint8_t* p = &px[(std::size_t(y) * w + x) * c];
      b.push_back(p[2]);
      b.push_back(p[1]);
      b.push_back(p[0]);
      if (c == 4) b.push_back(p[3]);
    }
    for (std::uint32_t k = w * c; k < stride; ++k) b.push_back(0);
  }
  return b;
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
  write_raw(dir + "/a.jpg", jpeg_encode(w, h, 3, px));
  imageio::Image j = imageio::load(dir + "/a.jpg");
  EXPECT_EQ(j.width, w);
  EXPECT_EQ(j.height, h);
  EXPECT_EQ(j.channels, 3);
  for (std::size_t i = 0; i < px.size(); ++i) EXPECT_NEAR(j.u8[i], px[i], 4) << i;

  Bytes px4 = pattern(7, 5, 3);
  write_raw(dir + "/a.bmp", bmp_encode(7, 5, 3, px4));
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
  Bytes jpg = jpeg_encode(32, 32, 3, px);
  std::string path = dir + "/t.jpg";
  for (std::size_t n : {3ul, 10ul, jpg.size() / 2, jpg.size() - 2, jpg.size() - 1}) {
    write_raw(path, Bytes(jpg.begin(), jpg.begin() + n));
    expect_error([&] { imageio::load(path); }, path, "JPEG");
  }
  Bytes bmp = bmp_encode(9, 7, 3, pattern(9, 7, 3));
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

// ---- hostile inputs (issue 12, findings 1-3) ------------------------------------------------

namespace {

// The segments of a JPEG as (marker, whole segment bytes); entropy-coded data stays
// attached to its SOS segment.
std::vector<std::pair<int, Bytes>> jpeg_segments(const Bytes& j) {
  std::vector<std::pair<int, Bytes>> segs;
  std::size_t pos = 2;
  while (pos + 4 <= j.size()) {
    int m = j[pos + 1];
    if (m == 0xD9) break;
    std::size_t len = (j[pos + 2] << 8) | j[pos + 3];
    std::size_t end = pos + 2 + len;
    if (m == 0xDA) {
      while (end + 1 < j.size() && !(j[end] == 0xFF && j[end + 1] != 0 && (j[end + 1] < 0xD0 || j[end + 1] > 0xD7)))
        ++end;
    }
    segs.emplace_back(m, Bytes(j.begin() + pos, j.begin() + end));
    pos = end;
  }
  return segs;
}

Bytes jpeg_join(const std::vector<std::pair<int, Bytes>>& segs) {
  Bytes out = {0xFF, 0xD8};
  for (const auto& s : segs) out.insert(out.end(), s.second.begin(), s.second.end());
  out.push_back(0xFF);
  out.push_back(0xD9);
  return out;
}

// A JPEG of SOI, SOF0 declaring w x h, a DQT, a DHT, an SOS and a few bytes of
// scan data, EOI: ~200 bytes that ask for w * h pixels.
Bytes tiny_jpeg_header(int w, int h) {
  Bytes b = {0xFF, 0xD8};
  b.insert(b.end(), {0xFF, 0xDB, 0x00, 0x43, 0x00});  // DQT, table 0: all ones
  for (int i = 0; i < 64; ++i) b.push_back(1);
  b.insert(b.end(), {0xFF, 0xC0, 0x00, 0x11, 0x08, std::uint8_t(h >> 8), std::uint8_t(h), std::uint8_t(w >> 8),
                     std::uint8_t(w), 0x03});
  for (int c = 1; c <= 3; ++c) b.insert(b.end(), {std::uint8_t(c), 0x11, 0x00});
  // DHT: DC table 0 and AC table 0 with a single 1-bit code each.
  b.insert(b.end(), {0xFF, 0xC4, 0x00, 0x28, 0x00, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0x00,
                     0x10, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0x00});
  b.insert(b.end(), {0xFF, 0xDA, 0x00, 0x0C, 0x03, 1, 0x00, 2, 0x00, 3, 0x00, 0x00, 0x3F, 0x00});
  for (int i = 0; i < 64; ++i) b.push_back(0x00);
  b.insert(b.end(), {0xFF, 0xD9});
  return b;
}

// A PNG with an IHDR declaring w x h (8-bit RGB), one tiny IDAT and IEND: valid CRCs.
Bytes tiny_png_header(std::uint32_t w, std::uint32_t h) {
  Bytes png = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
  Bytes ihdr;
  put_be32(ihdr, w);
  put_be32(ihdr, h);
  ihdr.insert(ihdr.end(), {8, 2, 0, 0, 0});
  add_chunk(png, "IHDR", ihdr);
  add_chunk(png, "IDAT", {0x78, 0x01, 0x01, 0x00, 0x00, 0xFF, 0xFF, 0x00, 0x00, 0x00, 0x01});
  add_chunk(png, "IEND", {});
  return png;
}

long vm_hwm_kb() {
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::stol(line.substr(6));
  return -1;
}

}  // namespace

TEST(ImageIoHostile, HuffmanTableOverflowJpegIsAnError) {
  // Finding 1: this 14-byte JPEG made stb write past its Huffman arrays.
  std::string dir = test_dir();
  const Bytes j = {0xff, 0xd8, 0xff, 0xc4, 0x00, 0x03, 0x00, 0xff, 0xda, 0x00, 0x03, 0x26, 0xff, 0xd9};
  write_raw(dir + "/h.jpg", j);
  expect_error([&] { imageio::load(dir + "/h.jpg"); }, dir + "/h.jpg", "corrupt JPEG");
  expect_error([&] { imageio::decode(j.data(), j.size(), "mem.jpg", 3, false, {}); }, "mem.jpg", "JPEG");
  expect_error([&] { imageio::probe(dir + "/h.jpg"); }, dir + "/h.jpg", "corrupt JPEG");
}

TEST(ImageIoHostile, ProgressiveJpegWithoutOrWithBadHuffmanTables) {
  // Finding 2: stb read uninitialised tables of progressive JPEGs lacking a DHT.
  std::string dir = test_dir();
  Bytes px = pattern(40, 24, 3);
  Bytes prog = jpeg_encode(40, 24, 3, px, 90, true);
  auto segs = jpeg_segments(prog);
  ASSERT_TRUE(std::any_of(segs.begin(), segs.end(), [](const auto& s) { return s.first == 0xC2; }));
  imageio::Image ok = imageio::decode(prog.data(), prog.size(), "p.jpg", 3, false, {});
  EXPECT_EQ(ok.width, 40);

  // Every DHT removed.
  std::vector<std::pair<int, Bytes>> no_dht;
  for (const auto& s : segs)
    if (s.first != 0xC4) no_dht.push_back(s);
  ASSERT_LT(no_dht.size(), segs.size());
  Bytes a = jpeg_join(no_dht);
  expect_error([&] { imageio::decode(a.data(), a.size(), "nodht.jpg", 3, false, {}); }, "nodht.jpg",
               "cannot decode JPEG");

  // Each DHT in turn removed, and each made bogus (its 16 code counts all 255).
  int cases = 0;
  for (std::size_t i = 0; i < segs.size(); ++i) {
    if (segs[i].first != 0xC4) continue;
    auto drop = segs;
    drop.erase(drop.begin() + i);
    Bytes d = jpeg_join(drop);
    try {
      imageio::decode(d.data(), d.size(), "drop.jpg", 3, false, {});  // a table may be unused by the scans
    } catch (const imageio::Error& e) {
      EXPECT_EQ(std::string(e.what()).rfind("drop.jpg: ", 0), 0u) << e.what();
    }
    auto bad = segs;
    for (int k = 0; k < 16; ++k) bad[i].second[5 + k] = 0xFF;
    Bytes b = jpeg_join(bad);
    expect_error([&] { imageio::decode(b.data(), b.size(), "bad.jpg", 3, false, {}); }, "bad.jpg", "JPEG");
    ++cases;
  }
  EXPECT_GT(cases, 0);
}

TEST(ImageIoHostile, DamagedJpegsNeverCrash) {
  // Every byte of a progressive and a baseline JPEG flipped in turn: an Error or an
  // image, never a crash (run under ASan to see more).
  Bytes px = pattern(24, 16, 3);
  for (bool progressive : {false, true}) {
    Bytes j = jpeg_encode(24, 16, 3, px, 80, progressive);
    int errors = 0;
    for (std::size_t i = 2; i < j.size(); ++i) {
      Bytes d = j;
      d[i] ^= 0x5A;
      try {
        imageio::Image img = imageio::decode(d.data(), d.size(), "x.jpg", 0, false, {});
        EXPECT_EQ(img.u8.size(), std::size_t(img.width) * img.height * img.channels);
      } catch (const imageio::Error& e) {
        ++errors;
        EXPECT_EQ(std::string(e.what()).rfind("x.jpg: ", 0), 0u);
      }
    }
    EXPECT_GT(errors, 0);
  }
}

TEST(ImageIoHostile, DecompressionBombsAreRefusedFromTheHeader) {
  // Finding 3: a ~200-byte JPEG declaring 18900x18900 and a PNG declaring 18000x18000.
  std::string dir = test_dir();
  Bytes j = tiny_jpeg_header(18900, 18900);
  EXPECT_LT(j.size(), 260u);
  write_raw(dir + "/bomb.jpg", j);
  expect_error([&] { imageio::load(dir + "/bomb.jpg", 3); }, dir + "/bomb.jpg",
               "image is 18900x18900 (341 Mpx), above the limit of 64 Mpx (raise it with --max-pixels)");
  Bytes p = tiny_png_header(18000, 18000);
  write_raw(dir + "/bomb.png", p);
  expect_error([&] { imageio::load(dir + "/bomb.png"); }, dir + "/bomb.png",
               "image is 18000x18000 (309 Mpx), above the limit of 64 Mpx");
  // The header probe reports the size without decoding.
  imageio::ImageInfo pi = imageio::probe(dir + "/bomb.png");
  EXPECT_EQ(pi.format, "PNG");
  EXPECT_EQ(pi.width, 18000);
  EXPECT_EQ(pi.height, 18000);
  EXPECT_EQ(pi.channels, 3);
  imageio::ImageInfo ji = imageio::probe(dir + "/bomb.jpg");
  EXPECT_EQ(ji.format, "JPEG");
  EXPECT_EQ(ji.width, 18900);
}

TEST(ImageIoHostile, HugeHeadersAreRefusedBeforeAllocation) {
  // 100000x100000 PNG (10^10 pixels) and the largest JPEG (65535x65535; JPEG sizes are
  // 16-bit): refused with peak RSS far below one decoded row band. Run in a child
  // process so that other tests' memory does not count.
  Bytes p = tiny_png_header(100000, 100000);
  Bytes j = tiny_jpeg_header(65535, 65535);
  pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    int code = 0;
    long before = vm_hwm_kb();
    for (int rep = 0; rep < 3; ++rep) {
      for (const Bytes* b : {&p, &j}) {
        try {
          imageio::decode(b->data(), b->size(), "huge", 3, false, {});
          code |= 1;
        } catch (const imageio::Error& e) {
          if (!std::strstr(e.what(), "above the limit")) code |= 2;
        }
      }
    }
    long after = vm_hwm_kb();
    if (before < 0 || after < 0) code |= 4;
    if (after > 100 * 1024) code |= 8;
    if (after - before > 10 * 1024) code |= 16;
    std::fflush(nullptr);
    ::_exit(code);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "1: decoded, 2: other error, 4: no VmHWM, 8: peak RSS > 100 MB, "
                                       "16: peak RSS grew by > 10 MB";
}

TEST(ImageIoLimits, LimitIsOverridable) {
  std::string dir = test_dir();
  Bytes px = pattern(100, 60, 3);
  imageio::save_png(dir + "/a.png", px.data(), 100, 60, 3);
  write_raw(dir + "/a.jpg", jpeg_encode(100, 60, 3, px));
  write_raw(dir + "/a.bmp", bmp_encode(100, 60, 3, px));
  imageio::DecodeLimits small;
  small.max_pixels = 5999;
  imageio::DecodeLimits exact;
  exact.max_pixels = 6000;
  for (const char* ext : {"png", "jpg", "bmp"}) {
    std::string path = dir + "/a." + ext;
    expect_error([&] { imageio::load(path, 3, false, small); }, path, "image is 100x60 (0.00572 Mpx), above the limit");
    imageio::Image img = imageio::load(path, 3, false, exact);
    EXPECT_EQ(img.width, 100);
    EXPECT_EQ(img.height, 60);
  }
  std::uint64_t v = 0;
  EXPECT_TRUE(imageio::parse_max_pixels("64", &v));
  EXPECT_EQ(v, 64ull << 20);
  EXPECT_TRUE(imageio::parse_max_pixels("0.5", &v));
  EXPECT_EQ(v, 1ull << 19);
  for (const char* bad : {"", "0", "-1", "abc", "1e30", "nan", "5x"}) EXPECT_FALSE(imageio::parse_max_pixels(bad, &v)) << bad;
  EXPECT_EQ(imageio::megapixels_text(64ull << 20), "64");
  EXPECT_EQ(imageio::megapixels_text(100000ull * 100000ull), "9537");
}

TEST(ImageIoProbe, HeaderMatchesTheDecodedImage) {
  std::string dir = test_dir();
  Bytes px = pattern(31, 17, 4);
  imageio::save_png(dir + "/a.png", px.data(), 31, 17, 4);
  Bytes rgb = pattern(31, 17, 3);
  write_raw(dir + "/a.jpg", jpeg_encode(31, 17, 3, rgb));
  write_raw(dir + "/a.bmp", bmp_encode(31, 17, 4, px, true));
  std::vector<std::uint16_t> s(12, 300);
  write_raw(dir + "/d.png", png16(4, 3, 1, s));
  for (const char* f : {"a.png", "a.jpg", "a.bmp", "d.png"}) {
    std::string path = dir + "/" + f;
    imageio::ImageInfo info = imageio::probe(path);
    imageio::Image img = imageio::load(path, 0, true);
    EXPECT_EQ(info.width, img.width) << f;
    EXPECT_EQ(info.height, img.height) << f;
    EXPECT_EQ(info.channels, img.channels) << f;
    EXPECT_EQ(info.bit_depth == 16 ? 16 : 8, img.bit_depth) << f;
  }
  EXPECT_EQ(imageio::probe(dir + "/d.png").bit_depth, 16);
  // A top-down 32-bit BMP keeps its alpha and row order.
  EXPECT_EQ(imageio::load(dir + "/a.bmp").u8, px);

  // A JPEG whose frame header sits behind 130 KB of APP segments: probe reads on.
  Bytes j = jpeg_encode(31, 17, 3, rgb);
  Bytes big = {0xFF, 0xD8};
  for (int k = 0; k < 2; ++k) {
    big.insert(big.end(), {0xFF, 0xE1, 0xFF, 0xFF});
    big.insert(big.end(), 0xFFFF - 2, 0x20);
  }
  big.insert(big.end(), j.begin() + 2, j.end());
  write_raw(dir + "/big.jpg", big);
  EXPECT_EQ(imageio::probe(dir + "/big.jpg").width, 31);
  EXPECT_EQ(imageio::load(dir + "/big.jpg").width, 31);

  // Truncated headers and other files.
  write_raw(dir + "/t.png", Bytes(j.begin(), j.begin() + 5));
  expect_error([&] { imageio::probe(dir + "/t.png"); }, dir + "/t.png", "truncated JPEG");
  expect_error([&] { imageio::probe(dir + "/missing.png"); }, dir + "/missing.png", "cannot open");
  expect_error([&] { imageio::probe(dir); }, dir, "not a regular file");
  write_raw(dir + "/e.png", {});
  expect_error([&] { imageio::probe(dir + "/e.png"); }, dir + "/e.png", "empty file");
}

TEST(ImageIoSpecialFiles, FifoIsRefusedWithoutBlocking) {
  std::string dir = test_dir();
  std::string fifo = dir + "/pipe.png";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0) << std::strerror(errno);
  for (int which = 0; which < 2; ++which) {
    auto fut = std::async(std::launch::async, [&] {
      try {
        if (which == 0)
          imageio::load(fifo);
        else
          imageio::probe(fifo);
        return std::string("no error");
      } catch (const imageio::Error& e) {
        return std::string(e.what());
      }
    });
    if (fut.wait_for(std::chrono::seconds(5)) != std::future_status::ready) {
      ADD_FAILURE() << "opening a FIFO blocked";
      int fd = ::open(fifo.c_str(), O_RDWR | O_NONBLOCK);  // unblocks the reader
      if (fd >= 0) ::close(fd);
    }
    EXPECT_EQ(fut.get(), fifo + ": not a regular file");
  }
  // /dev/null is not a regular file either.
  expect_error([&] { imageio::load("/dev/null"); }, "/dev/null", "not a regular file");
}

TEST(ImageIo, MemoryDecodeMatchesLoad) {
  std::string dir = test_dir();
  Bytes px = pattern(13, 11, 3);
  Bytes png = imageio::encode_png(px.data(), 13, 11, 3);
  imageio::Image m = imageio::decode(png.data(), png.size(), "mem", 0, false, {});
  EXPECT_EQ(m.u8, px);
  expect_error([&] { imageio::decode(nullptr, 0, "mem", 0, false, {}); }, "mem", "empty file");
  expect_error([&] { imageio::decode(png.data(), png.size(), "mem", 5, false, {}); }, "mem", "channel count");
  // Large round trip at the demo's size.
  Bytes big = pattern(1920, 1280, 3);
  Bytes enc = imageio::encode_png(big.data(), 1920, 1280, 3);
  EXPECT_EQ(imageio::decode(enc.data(), enc.size(), "big", 3, false, {}).u8, big);
}

TEST(ImageIo, MessagesStayOneLineEvenForHostileFileNames) {
  std::string dir = test_dir();
  std::string name = dir + "/a\nb\x1b[31m.png";
  write_raw(name, Bytes{'x', 'y'});
  for (int which = 0; which < 2; ++which) {
    try {
      if (which == 0)
        imageio::load(name);
      else
        imageio::load(dir + "/missing\r\n.png");
      ADD_FAILURE() << "no error";
    } catch (const imageio::Error& e) {
      std::string msg = e.what();
      for (char ch : msg) EXPECT_FALSE(static_cast<unsigned char>(ch) < 32 || ch == 127) << msg;
      EXPECT_NE(msg.find(which == 0 ? "a?b?[31m.png: unsupported image format" : "missing??.png: cannot open"),
                std::string::npos)
          << msg;
    }
  }
}
