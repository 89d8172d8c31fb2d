// Image files for the apps, on top of stb_image / stb_image_write.
//
// stb decodes leniently: a JPEG or BMP cut short decodes "successfully" with grey or
// black rows, and stb never checks PNG CRCs. Users must learn that their file is
// damaged, so before handing bytes to stb we walk the container structure (PNG chunks
// with CRCs, JPEG markers up to EOI, BMP pixel-array size) and reject anything that
// is truncated or corrupt with "path: problem".
#include "apps/common/image_io.h"

#include "apps/common/output_files.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>

#define STBI_ONLY_PNG
#define STBI_ONLY_JPEG
#define STBI_ONLY_BMP
#define STBI_NO_STDIO
#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#define STBI_WRITE_NO_STDIO
#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wunused-parameter"
#pragma GCC diagnostic ignored "-Wsign-compare"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wimplicit-fallthrough"
#include "stb_image.h"
#include "stb_image_write.h"
#pragma GCC diagnostic pop

namespace imageio {
namespace {

// Larger files are certainly not camera frames; refusing them bounds memory use.
constexpr std::uint64_t kMaxFileBytes = 1ull << 30;
// Decoded size limit (bytes), against decompression bombs with huge declared sizes.
constexpr std::uint64_t kMaxDecodedBytes = 1ull << 30;

[[noreturn]] void fail(const std::string& path, const std::string& problem) {
  throw Error(path + ": " + problem);
}

std::string errno_text(int err) { return std::strerror(err); }

std::vector<std::uint8_t> read_whole_file(const std::string& path) {
  int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) fail(path, "cannot open: " + errno_text(errno));
  struct stat st;
  if (::fstat(fd, &st) != 0) {
    int err = errno;
    ::close(fd);
    fail(path, "cannot stat: " + errno_text(err));
  }
  if (!S_ISREG(st.st_mode)) {
    ::close(fd);
    fail(path, "not a regular file");
  }
  if (static_cast<std::uint64_t>(st.st_size) > kMaxFileBytes) {
    ::close(fd);
    fail(path, "file too large (" + std::to_string(st.st_size) + " bytes)");
  }
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(st.st_size));
  std::size_t got = 0;
  while (got < bytes.size()) {
    ssize_t n = ::read(fd, bytes.data() + got, bytes.size() - got);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      int err = errno;
      ::close(fd);
      fail(path, "read error: " + errno_text(err));
    }
    if (n == 0) break;  // the file shrank while we read it
    got += static_cast<std::size_t>(n);
  }
  ::close(fd);
  bytes.resize(got);
  return bytes;
}

std::uint32_t be32(const std::uint8_t* p) {
  return (std::uint32_t(p[0]) << 24) | (std::uint32_t(p[1]) << 16) | (std::uint32_t(p[2]) << 8) |
         std::uint32_t(p[3]);
}
std::uint32_t le32(const std::uint8_t* p) {
  return std::uint32_t(p[0]) | (std::uint32_t(p[1]) << 8) | (std::uint32_t(p[2]) << 16) |
         (std::uint32_t(p[3]) << 24);
}
std::uint16_t le16(const std::uint8_t* p) { return std::uint16_t(p[0] | (p[1] << 8)); }

enum class Format { Png, Jpeg, Bmp, Unknown };

Format sniff(const std::vector<std::uint8_t>& b) {
  static const std::uint8_t png_sig[8] = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
  if (b.size() >= 8 && std::memcmp(b.data(), png_sig, 8) == 0) return Format::Png;
  if (b.size() >= 3 && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF) return Format::Jpeg;
  if (b.size() >= 2 && b[0] == 'B' && b[1] == 'M') return Format::Bmp;
  return Format::Unknown;
}

const char* format_name(Format f) {
  switch (f) {
    case Format::Png: return "PNG";
    case Format::Jpeg: return "JPEG";
    case Format::Bmp: return "BMP";
    default: return "image";
  }
}

// CRC-32 (ISO 3309, as PNG uses), slicing by 8 so checking a full-HD PNG costs ~1 ms.
struct CrcTables {
  std::uint32_t t[8][256];
  CrcTables() {
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[0][i] = c;
    }
    for (int s = 1; s < 8; ++s)
      for (int i = 0; i < 256; ++i) t[s][i] = (t[s - 1][i] >> 8) ^ t[0][t[s - 1][i] & 0xFF];
  }
};

std::uint32_t crc32(const std::uint8_t* p, std::size_t n) {
  static const CrcTables tab;
  const auto& t = tab.t;
  std::uint32_t c = 0xFFFFFFFFu;
  while (n >= 8) {
    std::uint32_t lo = c ^ le32(p), hi = le32(p + 4);
    c = t[7][lo & 0xFF] ^ t[6][(lo >> 8) & 0xFF] ^ t[5][(lo >> 16) & 0xFF] ^ t[4][lo >> 24] ^
        t[3][hi & 0xFF] ^ t[2][(hi >> 8) & 0xFF] ^ t[1][(hi >> 16) & 0xFF] ^ t[0][hi >> 24];
    p += 8;
    n -= 8;
  }
  while (n--) c = t[0][(c ^ *p++) & 0xFF] ^ (c >> 8);
  return c ^ 0xFFFFFFFFu;
}

std::string chunk_name(const std::uint8_t* p) {
  std::string s;
  for (int i = 0; i < 4; ++i) s += (p[i] >= 32 && p[i] < 127) ? char(p[i]) : '?';
  return s;
}

void check_png(const std::string& path, const std::vector<std::uint8_t>& b) {
  std::size_t pos = 8;
  bool first = true;
  for (;;) {
    if (b.size() - pos < 12)
      fail(path, "truncated PNG (file ends at byte " + std::to_string(b.size()) +
                     " before the IEND chunk)");
    std::uint32_t len = be32(&b[pos]);
    std::string name = chunk_name(&b[pos + 4]);
    if (len > 0x7FFFFFFFu) fail(path, "corrupt PNG (chunk '" + name + "' has an invalid length)");
    if (b.size() - pos - 12 < len)
      fail(path, "truncated PNG (chunk '" + name + "' at byte " + std::to_string(pos) + " needs " +
                     std::to_string(len) + " bytes, file ends at byte " +
                     std::to_string(b.size()) + ")");
    if (first && name != "IHDR") fail(path, "corrupt PNG (first chunk is not IHDR)");
    first = false;
    std::uint32_t stored = be32(&b[pos + 8 + len]);
    if (crc32(&b[pos + 4], len + 4) != stored)
      fail(path, "corrupt PNG (CRC mismatch in chunk '" + name + "' at byte " +
                     std::to_string(pos) + ")");
    pos += 12 + std::size_t(len);
    if (name == "IEND") return;
  }
}

bool jpeg_standalone_marker(std::uint8_t m) { return m == 0x01 || (m >= 0xD0 && m <= 0xD7); }

void check_jpeg(const std::string& path, const std::vector<std::uint8_t>& b) {
  const std::size_t n = b.size();
  std::size_t pos = 2;  // after SOI
  bool seen_scan = false;
  for (;;) {
    // Some writers leave junk between segments; libjpeg tolerates it, so do we.
    while (pos < n && b[pos] != 0xFF) ++pos;
    while (pos < n && b[pos] == 0xFF) ++pos;  // fill bytes
    if (pos >= n) break;
    std::uint8_t m = b[pos++];
    if (m == 0xD9) {
      if (!seen_scan) fail(path, "corrupt JPEG (end of image before any scan)");
      return;
    }
    if (jpeg_standalone_marker(m) || m == 0x00) continue;
    if (n - pos < 2) break;
    std::size_t len = (std::size_t(b[pos]) << 8) | b[pos + 1];
    if (len < 2) fail(path, "corrupt JPEG (segment length " + std::to_string(len) + ")");
    if (n - pos < len) break;
    pos += len;
    if (m == 0xDA) {
      seen_scan = true;
      // Entropy-coded data: FF is followed by 00 (stuffing) or a restart marker; any
      // other byte ends the scan.
      for (;;) {
        while (pos < n && b[pos] != 0xFF) ++pos;
        if (n - pos < 2) {
          pos = n;
          break;
        }
        std::uint8_t next = b[pos + 1];
        if (next == 0x00 || (next >= 0xD0 && next <= 0xD7)) {
          pos += 2;
        } else if (next == 0xFF) {
          pos += 1;
        } else {
          break;  // pos at the marker's FF
        }
      }
      if (pos >= n) break;
    }
  }
  fail(path, "truncated JPEG (file ends at byte " + std::to_string(n) +
                 " before the end-of-image marker)");
}

void check_bmp(const std::string& path, const std::vector<std::uint8_t>& b) {
  if (b.size() < 26) fail(path, "truncated BMP (header incomplete)");
  std::uint32_t off_bits = le32(&b[10]);
  std::uint32_t info_size = le32(&b[14]);
  std::int64_t width, height;
  std::uint32_t bpp, compression = 0;
  if (info_size == 12) {
    width = le16(&b[18]);
    height = static_cast<std::int16_t>(le16(&b[20]));
    bpp = le16(&b[24]);
  } else {
    if (info_size < 40 || b.size() < 34) fail(path, "truncated or unsupported BMP header");
    width = static_cast<std::int32_t>(le32(&b[18]));
    height = static_cast<std::int32_t>(le32(&b[22]));
    bpp = le16(&b[28]);
    compression = le32(&b[30]);
  }
  if (width <= 0 || height == 0) fail(path, "corrupt BMP (invalid size)");
  // Only uncompressed layouts have a size we can check; stb rejects RLE itself.
  if (compression != 0 && compression != 3 && compression != 6) return;
  std::uint64_t stride = ((std::uint64_t(width) * bpp + 31) / 32) * 4;
  std::uint64_t rows = std::uint64_t(height < 0 ? -height : height);
  if (stride > kMaxDecodedBytes || rows > kMaxDecodedBytes) fail(path, "BMP too large");
  std::uint64_t need = std::uint64_t(off_bits) + stride * rows;
  if (need > b.size())
    fail(path, "truncated BMP (pixel data needs " + std::to_string(need) +
                   " bytes, file has " + std::to_string(b.size()) + ")");
}

struct StbFree {
  void operator()(void* p) const { stbi_image_free(p); }
};

}  // namespace

Image load(const std::string& path, int want_channels, bool keep_16bit) {
  if (want_channels < 0 || want_channels > 4)
    fail(path, "invalid channel count requested (" + std::to_string(want_channels) + ")");
  std::vector<std::uint8_t> bytes = read_whole_file(path);
  if (bytes.empty()) fail(path, "empty file");
  Format format = sniff(bytes);
  switch (format) {
    case Format::Png: check_png(path, bytes); break;
    case Format::Jpeg: check_jpeg(path, bytes); break;
    case Format::Bmp: check_bmp(path, bytes); break;
    case Format::Unknown: fail(path, "unsupported image format (expected PNG, JPEG or BMP)");
  }
  if (bytes.size() > std::size_t(std::numeric_limits<int>::max()))
    fail(path, "file too large");
  const int len = static_cast<int>(bytes.size());

  int w = 0, h = 0, comp = 0;
  if (!stbi_info_from_memory(bytes.data(), len, &w, &h, &comp))
    fail(path, std::string("cannot decode ") + format_name(format) + ": " + stbi_failure_reason());
  const bool sixteen = format == Format::Png && keep_16bit && stbi_is_16_bit_from_memory(bytes.data(), len);
  const int out_channels = want_channels ? want_channels : comp;
  if (w <= 0 || h <= 0 ||
      std::uint64_t(w) * std::uint64_t(h) * std::uint64_t(out_channels) * (sixteen ? 2 : 1) >
          kMaxDecodedBytes)
    fail(path, "image too large (" + std::to_string(w) + "x" + std::to_string(h) + ")");

  Image img;
  int got_w = 0, got_h = 0, got_comp = 0;
  if (sixteen) {
    std::unique_ptr<stbi_us, StbFree> px(
        stbi_load_16_from_memory(bytes.data(), len, &got_w, &got_h, &got_comp, want_channels));
    if (!px) fail(path, std::string("cannot decode PNG: ") + stbi_failure_reason());
    img.bit_depth = 16;
    img.u16.assign(px.get(), px.get() + std::size_t(got_w) * got_h * out_channels);
  } else {
    std::unique_ptr<stbi_uc, StbFree> px(
        stbi_load_from_memory(bytes.data(), len, &got_w, &got_h, &got_comp, want_channels));
    if (!px)
      fail(path, std::string("cannot decode ") + format_name(format) + ": " + stbi_failure_reason());
    img.bit_depth = 8;
    img.u8.assign(px.get(), px.get() + std::size_t(got_w) * got_h * out_channels);
  }
  if (got_w != w || got_h != h) fail(path, "inconsistent image header");
  img.width = got_w;
  img.height = got_h;
  img.channels = out_channels;
  return img;
}

std::vector<std::uint8_t> encode_png(const std::uint8_t* pixels, int width, int height,
                                     int channels) {
  if (!pixels) throw Error("encode_png: no pixel data");
  if (width <= 0 || height <= 0 || channels < 1 || channels > 4)
    throw Error("encode_png: invalid image shape " + std::to_string(width) + "x" +
                std::to_string(height) + "x" + std::to_string(channels));
  if (std::uint64_t(width) * channels * height > std::uint64_t(std::numeric_limits<int>::max()) / 2)
    throw Error("encode_png: image too large");
  std::vector<std::uint8_t> out;
  auto append = [](void* ctx, void* data, int size) {
    auto* v = static_cast<std::vector<std::uint8_t>*>(ctx);
    auto* d = static_cast<const std::uint8_t*>(data);
    v->insert(v->end(), d, d + size);
  };
  if (!stbi_write_png_to_func(append, &out, width, height, channels, pixels, width * channels))
    throw Error("encode_png: PNG encoder failed (out of memory?)");
  return out;
}

void save_png(const std::string& path, const std::uint8_t* pixels, int width, int height,
              int channels) {
  std::vector<std::uint8_t> png;
  try {
    png = encode_png(pixels, width, height, channels);
  } catch (const Error& e) {
    fail(path, e.what());
  }
  try {
    outputs::write_file(path, png.data(), png.size());
  } catch (const outputs::Error& e) {
    throw Error(e.what());
  }
}

}  // namespace imageio
