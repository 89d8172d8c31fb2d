#include "shle/disparity_io.h"

#include "weights/quote_name.h"

#include <cmath>
#include <cstring>
#include <vector>

#include "shle/error.h"
#include "shle/file_read.h"

namespace shle {
namespace {

constexpr int kMaxSide = 1 << 15;

void check_size(int width, int height, const std::string& source) {
  if (width < 1 || height < 1 || width > kMaxSide || height > kMaxSide)
    throw Error(source + ": bad disparity size " + std::to_string(width) + "x" + std::to_string(height));
}

}  // namespace

DisparityMap parse_dat(const std::uint8_t* bytes, std::size_t size, int width, int height,
                       int fraction_bits, const std::string& source) {
  check_size(width, height, source);
  if (fraction_bits < 0 || fraction_bits > 15)
    throw Error(source + ": fraction bits must be 0..15, got " + std::to_string(fraction_bits));
  std::size_t n = static_cast<std::size_t>(width) * height;
  if (size != 2 * n)
    throw Error(source + ": " + std::to_string(size) + " bytes, expected " + std::to_string(2 * n) + " (" +
                std::to_string(width) + "x" + std::to_string(height) + " uint16)");
  DisparityMap m;
  m.width = width;
  m.height = height;
  m.d.resize(n);
  // Dividing by a power of two is exact in float for 16-bit integers.
  const float inv = 1.0f / static_cast<float>(1 << fraction_bits);
  for (std::size_t i = 0; i < n; ++i) {
    unsigned raw = bytes[2 * i] | (static_cast<unsigned>(bytes[2 * i + 1]) << 8);
    m.d[i] = static_cast<float>(raw) * inv;
  }
  return m;
}

DisparityMap read_dat(const std::string& path, int width, int height, int fraction_bits) {
  check_size(width, height, path);
  const std::uint64_t want = 2ull * static_cast<std::uint64_t>(width) * static_cast<std::uint64_t>(height);
  std::vector<std::uint8_t> bytes;
  try {
    bytes = read_file_bytes(path, want);
  } catch (const Error& e) {
    if (std::string(e.what()).find("larger than the limit") == std::string::npos) throw;
    throw Error(path + ": more than " + std::to_string(want) + " bytes, expected " + std::to_string(want) + " (" +
                std::to_string(width) + "x" + std::to_string(height) + " uint16)");
  }
  return parse_dat(bytes.data(), bytes.size(), width, height, fraction_bits, path);
}

int dat_fraction_bits(const std::string& file_name, int fallback) {
  const std::string prefix = "disparity_";
  if (file_name.compare(0, prefix.size(), prefix) != 0) return fallback;
  std::size_t i = prefix.size(), j = i;
  while (j < file_name.size() && j - i < 2 && file_name[j] >= '0' && file_name[j] <= '9') ++j;
  if (j == i || j >= file_name.size() || file_name[j] != '_') return fallback;
  int bits = std::stoi(file_name.substr(i, j - i));
  return bits <= 15 ? bits : fallback;
}

DisparityMap parse_pfm(const std::uint8_t* bytes, std::size_t size, const std::string& source) {
  std::size_t pos = 0;
  auto is_space = [](std::uint8_t c) { return c == ' ' || c == '\n' || c == '\r' || c == '\t'; };
  auto token = [&](const char* what) {
    while (pos < size && is_space(bytes[pos])) ++pos;
    std::size_t start = pos;
    while (pos < size && !is_space(bytes[pos]) && pos - start < 32) ++pos;
    if (pos == start || pos >= size)
      throw Error(source + ": truncated PFM header (reading " + std::string(what) + ")");
    if (pos - start >= 32) throw Error(source + ": PFM header field too long (" + std::string(what) + ")");
    return std::string(reinterpret_cast<const char*>(bytes + start), pos - start);
  };
  if (size < 2 || bytes[0] != 'P' || (bytes[1] != 'f' && bytes[1] != 'F'))
    throw Error(source + ": not a PFM file (no 'Pf' signature)");
  if (bytes[1] == 'F') throw Error(source + ": colour PFM ('PF') is not a disparity map; expected 'Pf'");
  pos = 2;
  if (pos >= size || !is_space(bytes[pos])) throw Error(source + ": not a PFM file (no 'Pf' signature)");
  auto integer = [&](const char* what) {
    std::string t = token(what);
    for (char c : t)
      if (c < '0' || c > '9') throw Error(source + ": PFM " + std::string(what) + " " + weights::quote_name(t) + " is not a positive integer");
    if (t.size() > 6) throw Error(source + ": PFM " + std::string(what) + " " + t + " is too large");
    return std::stoi(t);
  };
  int width = integer("width");
  int height = integer("height");
  check_size(width, height, source);
  std::string scale_text = token("scale");
  char* end = nullptr;
  double scale = std::strtod(scale_text.c_str(), &end);
  if (end != scale_text.c_str() + scale_text.size() || !std::isfinite(scale) || scale == 0.0)
    throw Error(source + ": PFM scale " + weights::quote_name(scale_text) + " is not a non-zero number");
  // Exactly one whitespace byte separates the header from the data.
  if (pos >= size || !is_space(bytes[pos])) throw Error(source + ": truncated PFM header");
  ++pos;
  std::size_t n = static_cast<std::size_t>(width) * height;
  if (size - pos != 4 * n)
    throw Error(source + ": PFM data is " + std::to_string(size - pos) + " bytes, expected " +
                std::to_string(4 * n) + " (" + std::to_string(width) + "x" + std::to_string(height) + " float32)");
  bool little = scale < 0;
  DisparityMap m;
  m.width = width;
  m.height = height;
  m.d.resize(n);
  for (int row = 0; row < height; ++row) {
    const std::uint8_t* src = bytes + pos + 4 * static_cast<std::size_t>(row) * width;
    float* dst = m.d.data() + static_cast<std::size_t>(height - 1 - row) * width;
    for (int x = 0; x < width; ++x) {
      const std::uint8_t* b = src + 4 * x;
      std::uint32_t u = little ? (b[0] | b[1] << 8 | b[2] << 16 | static_cast<std::uint32_t>(b[3]) << 24)
                               : (b[3] | b[2] << 8 | b[1] << 16 | static_cast<std::uint32_t>(b[0]) << 24);
      std::memcpy(&dst[x], &u, 4);
    }
  }
  return m;
}

DisparityMap read_pfm(const std::string& path) {
  std::vector<std::uint8_t> bytes = read_file_bytes(path, 4096ull + 4ull * kMaxSide * kMaxSide);
  return parse_pfm(bytes.data(), bytes.size(), path);
}

DisparityMap disparity_from_u16(const std::uint16_t* raw, int width, int height, double scale,
                                const std::string& source) {
  check_size(width, height, source);
  if (!(scale > 0) || !std::isfinite(scale)) throw Error(source + ": disparity scale must be > 0");
  DisparityMap m;
  m.width = width;
  m.height = height;
  std::size_t n = static_cast<std::size_t>(width) * height;
  m.d.resize(n);
  for (std::size_t i = 0; i < n; ++i) m.d[i] = static_cast<float>(raw[i] / scale);
  return m;
}

}  // namespace shle
