// Image files for the apps: PNG with libpng, JPEG with libjpeg-turbo (libjpeg API),
// uncompressed 24/32-bit BMP with the small reader below.
//
// Every file goes through three stages, and only the last allocates pixel memory:
//  1. its header, parsed here (PNG IHDR, JPEG SOFn, BMP info header), gives the size,
//     which is checked against DecodeLimits::max_pixels;
//  2. the container is walked (PNG chunks with CRCs, JPEG markers up to EOI, the BMP
//     pixel-array size), so truncated or corrupt files are rejected with "path: problem";
//  3. the codec decodes, with libjpeg's warnings ("corrupt data", "premature end")
//     treated as errors and libpng's errors caught; both report through longjmp out
//     of C code, in functions that own no C++ objects.
// Channel conversions follow stb_image, which the apps used before, bit for bit.
#include "apps/common/image_io.h"

#include "apps/common/output_files.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <cstdlib>
#include <cstddef>
#include <cstring>
#include <limits>
#include <memory>
#include <new>

#include <jpeglib.h>
#include <jerror.h>
#include <png.h>

namespace imageio {
namespace {

// Larger files are certainly not camera frames; refusing them bounds memory use.
constexpr std::uint64_t kMaxFileBytes = 1ull << 30;
// Progressive JPEGs with thousands of tiny scans cost minutes of CPU; real files have ~10.
constexpr int kMaxJpegScans = 500;
// zlib level of encode_png: 1 with the SUB filter encodes the demo's 1920x1280 frame
// 4-5x faster than stb's level 8 with per-row filter choice did (docs/PERFORMANCE.md).
constexpr int kPngLevel = 1;

// Library messages and file names end up in our one-line errors: no control characters.
std::string one_line(const std::string& s) {
  std::string out;
  for (char ch : s) {
    unsigned char c = static_cast<unsigned char>(ch);
    out += (c < 32 || c == 127) ? '?' : ch;
  }
  return out;
}

[[noreturn]] void fail(const std::string& path, const std::string& problem) {
  throw Error(one_line(path + ": " + problem));
}

std::string errno_text(int err) { return std::strerror(err); }

// Opens a regular file without blocking: O_NONBLOCK makes open() of a FIFO return at
// once instead of waiting for a writer; fstat then refuses anything but a regular file,
// and blocking mode is restored for the reads.
int open_regular(const std::string& path, std::uint64_t* size) {
  int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY);
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
  int flags = ::fcntl(fd, F_GETFL);
  if (flags < 0 || ::fcntl(fd, F_SETFL, flags & ~O_NONBLOCK) != 0) {
    int err = errno;
    ::close(fd);
    fail(path, "cannot read: " + errno_text(err));
  }
  *size = static_cast<std::uint64_t>(st.st_size);
  return fd;
}

struct Fd {
  int fd;
  ~Fd() { ::close(fd); }
};

// Appends up to `want` bytes; returns false when the file ended before.
bool read_more(int fd, const std::string& path, std::vector<std::uint8_t>* bytes, std::size_t want) {
  std::size_t start = bytes->size();
  bytes->resize(start + want);
  std::size_t got = 0;
  bool eof = false;
  while (got < want) {
    ssize_t n = ::read(fd, bytes->data() + start + got, want - got);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) fail(path, "read error: " + errno_text(errno));
    if (n == 0) {
      eof = true;  // the file ends here (or shrank while we read it)
      break;
    }
    got += static_cast<std::size_t>(n);
  }
  bytes->resize(start + got);
  return !eof;
}

std::vector<std::uint8_t> read_whole_file(const std::string& path) {
  std::uint64_t size = 0;
  Fd f{open_regular(path, &size)};
  if (size > kMaxFileBytes) fail(path, "file too large (" + std::to_string(size) + " bytes)");
  std::vector<std::uint8_t> bytes;
  bytes.reserve(static_cast<std::size_t>(size));
  read_more(f.fd, path, &bytes, static_cast<std::size_t>(size));
  return bytes;
}

std::uint32_t be32(const std::uint8_t* p) {
  return (std::uint32_t(p[0]) << 24) | (std::uint32_t(p[1]) << 16) | (std::uint32_t(p[2]) << 8) |
         std::uint32_t(p[3]);
}
std::uint16_t be16(const std::uint8_t* p) { return std::uint16_t((p[0] << 8) | p[1]); }
std::uint32_t le32(const std::uint8_t* p) {
  return std::uint32_t(p[0]) | (std::uint32_t(p[1]) << 8) | (std::uint32_t(p[2]) << 16) |
         (std::uint32_t(p[3]) << 24);
}
std::uint16_t le16(const std::uint8_t* p) { return std::uint16_t(p[0] | (p[1] << 8)); }

enum class Format { Png, Jpeg, Bmp, Unknown };

Format sniff(const std::uint8_t* b, std::size_t n) {
  static const std::uint8_t png_sig[8] = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
  if (n >= 8 && std::memcmp(b, png_sig, 8) == 0) return Format::Png;
  if (n >= 3 && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF) return Format::Jpeg;
  if (n >= 2 && b[0] == 'B' && b[1] == 'M') return Format::Bmp;
  return Format::Unknown;
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

// ---- headers: stage 1 ----------------------------------------------------------------
// Each parser sees the first n bytes of the file; `complete` says whether that is the
// whole file. Without enough bytes it returns false (probe reads more) or, on the
// whole file, reports the truncation.

bool png_header(const std::uint8_t* b, std::size_t n, bool complete, const std::string& name,
                ImageInfo* info) {
  if (n < 33) {
    if (!complete) return false;
    fail(name, "truncated PNG (file ends at byte " + std::to_string(n) + " inside the header)");
  }
  if (be32(b + 8) != 13 || std::memcmp(b + 12, "IHDR", 4) != 0)
    fail(name, "corrupt PNG (first chunk is not IHDR)");
  if (crc32(b + 12, 17) != be32(b + 29)) fail(name, "corrupt PNG (CRC mismatch in chunk 'IHDR' at byte 8)");
  std::uint32_t w = be32(b + 16), h = be32(b + 20);
  int depth = b[24], ctype = b[25];
  if (w == 0 || h == 0 || w > 0x7FFFFFFFu || h > 0x7FFFFFFFu)
    fail(name, "corrupt PNG (invalid size " + std::to_string(w) + "x" + std::to_string(h) + ")");
  bool ok_depth = false;
  int channels = 0;
  switch (ctype) {
    case 0: channels = 1; ok_depth = depth == 1 || depth == 2 || depth == 4 || depth == 8 || depth == 16; break;
    case 2: channels = 3; ok_depth = depth == 8 || depth == 16; break;
    case 3: channels = 3; ok_depth = depth == 1 || depth == 2 || depth == 4 || depth == 8; break;
    case 4: channels = 2; ok_depth = depth == 8 || depth == 16; break;
    case 6: channels = 4; ok_depth = depth == 8 || depth == 16; break;
    default: break;
  }
  if (!ok_depth || b[26] != 0 || b[27] != 0 || b[28] > 1)
    fail(name, "corrupt PNG (invalid header: color type " + std::to_string(ctype) + ", bit depth " +
                   std::to_string(depth) + ")");
  // A tRNS chunk (before IDAT) adds an alpha channel, as libpng and stb expand it.
  if (ctype == 0 || ctype == 2 || ctype == 3) {
    std::size_t pos = 33;
    for (;;) {
      if (n - pos < 8) {
        if (!complete) return false;
        break;  // stage 2 reports the truncation
      }
      const std::uint8_t* c = b + pos + 4;
      if (std::memcmp(c, "tRNS", 4) == 0) {
        ++channels;
        break;
      }
      if (std::memcmp(c, "IDAT", 4) == 0 || std::memcmp(c, "IEND", 4) == 0) break;
      std::uint64_t next = pos + 12ull + be32(b + pos);
      if (next > n) {
        if (!complete) return false;
        break;
      }
      pos = static_cast<std::size_t>(next);
    }
  }
  info->format = "PNG";
  info->width = static_cast<int>(w);
  info->height = static_cast<int>(h);
  info->channels = channels;
  info->bit_depth = depth;
  return true;
}

bool jpeg_standalone_marker(std::uint8_t m) { return m == 0x01 || (m >= 0xD0 && m <= 0xD7); }

bool jpeg_header(const std::uint8_t* b, std::size_t n, bool complete, const std::string& name,
                 ImageInfo* info) {
  std::size_t pos = 2;  // after SOI
  for (;;) {
    while (pos < n && b[pos] != 0xFF) ++pos;
    while (pos < n && b[pos] == 0xFF) ++pos;
    if (pos >= n || n - pos < 3) break;
    std::uint8_t m = b[pos++];
    if (jpeg_standalone_marker(m) || m == 0x00) continue;
    if (m == 0xD9 || m == 0xDA) fail(name, "corrupt JPEG (no frame header before the first scan)");
    std::size_t len = be16(b + pos);
    if (len < 2) fail(name, "corrupt JPEG (segment length " + std::to_string(len) + ")");
    const bool sof = m >= 0xC0 && m <= 0xCF && m != 0xC4 && m != 0xC8 && m != 0xCC;
    if (!sof) {
      pos += len;
      continue;
    }
    if (n - pos < 8) break;
    if (len < 8) fail(name, "corrupt JPEG (frame header too short)");
    int precision = b[pos + 2];
    int h = be16(b + pos + 3), w = be16(b + pos + 5), comps = b[pos + 7];
    if (m != 0xC0 && m != 0xC1 && m != 0xC2 && m != 0xC9 && m != 0xCA)
      fail(name, "unsupported JPEG (lossless or hierarchical coding, SOF marker 0x" +
                     std::string(1, "0123456789ABCDEF"[m >> 4]) + "0123456789ABCDEF"[m & 15] + ")");
    if (precision != 8)
      fail(name, "unsupported JPEG (" + std::to_string(precision) + "-bit samples; only 8-bit JPEGs are read)");
    if (w == 0 || h == 0)
      fail(name, "corrupt JPEG (invalid size " + std::to_string(w) + "x" + std::to_string(h) + ")");
    if (comps != 1 && comps != 3 && comps != 4)
      fail(name, "unsupported JPEG (" + std::to_string(comps) + " color components)");
    info->format = "JPEG";
    info->width = w;
    info->height = h;
    info->channels = comps == 1 ? 1 : 3;  // CMYK / YCCK are converted to RGB, as stb did
    info->bit_depth = 8;
    return true;
  }
  if (!complete) return false;
  fail(name, "truncated JPEG (file ends at byte " + std::to_string(n) + " before the frame header)");
}

struct BmpLayout {
  std::uint32_t off_bits = 0, header_end = 0;
  int width = 0, height = 0, bpp = 0, channels = 0;
  bool top_down = false;
  bool zero_alpha_is_opaque = false;  // 32-bit BI_RGB: an all-zero alpha channel means "no alpha"
};

bool bmp_layout(const std::uint8_t* b, std::size_t n, bool complete, const std::string& name,
                BmpLayout* L) {
  if (n < 26 || (n < 54 && le32(b + 14) != 12)) {
    if (!complete) return false;
    fail(name, "truncated BMP (header incomplete)");
  }
  L->off_bits = le32(b + 10);
  std::uint32_t info_size = le32(b + 14);
  std::int64_t width, height;
  std::uint32_t compression = 0;
  if (info_size == 12) {
    width = le16(b + 18);
    height = static_cast<std::int16_t>(le16(b + 20));
    L->bpp = le16(b + 24);
    L->header_end = 26;
  } else {
    if (info_size < 40) fail(name, "unsupported BMP header (" + std::to_string(info_size) + " bytes)");
    width = static_cast<std::int32_t>(le32(b + 18));
    height = static_cast<std::int32_t>(le32(b + 22));
    L->bpp = le16(b + 28);
    compression = le32(b + 30);
    L->header_end = 14 + info_size;
  }
  if (width <= 0 || height == 0 || height == std::numeric_limits<std::int32_t>::min())
    fail(name, "corrupt BMP (invalid size " + std::to_string(width) + "x" + std::to_string(height) + ")");
  L->width = static_cast<int>(width);
  L->top_down = height < 0;
  L->height = static_cast<int>(height < 0 ? -height : height);
  const std::string unsupported = "unsupported BMP (" + std::to_string(L->bpp) + " bits per pixel, compression " +
                                  std::to_string(compression) + "; only uncompressed 24- and 32-bit BMPs are read)";
  if (compression == 0 && L->bpp == 24) {
    L->channels = 3;
  } else if (compression == 0 && L->bpp == 32) {
    L->channels = 4;
    L->zero_alpha_is_opaque = true;
  } else if (compression == 3 && L->bpp == 32) {
    // BI_BITFIELDS: only the standard BGRA byte order. The masks follow a 40-byte
    // header, or sit inside a larger one (which also carries an alpha mask).
    std::size_t need = info_size >= 56 ? 70 : 66;
    if (n < need) {
      if (!complete) return false;
      fail(name, "truncated BMP (header incomplete)");
    }
    std::uint32_t mr = le32(b + 54), mg = le32(b + 58), mb = le32(b + 62);
    std::uint32_t ma = info_size >= 56 ? le32(b + 66) : 0;
    if (mr != 0xFF0000u || mg != 0xFF00u || mb != 0xFFu || (ma != 0 && ma != 0xFF000000u)) fail(name, unsupported);
    if (info_size == 40) L->header_end += 12;
    L->channels = ma ? 4 : 3;
  } else {
    fail(name, unsupported);
  }
  if (L->off_bits < L->header_end) fail(name, "corrupt BMP (pixel data offset inside the header)");
  return true;
}

bool bmp_header(const std::uint8_t* b, std::size_t n, bool complete, const std::string& name, ImageInfo* info) {
  BmpLayout L;
  if (!bmp_layout(b, n, complete, name, &L)) return false;
  info->format = "BMP";
  info->width = L.width;
  info->height = L.height;
  info->channels = L.channels;
  info->bit_depth = 8;
  return true;
}

bool parse_header(const std::uint8_t* b, std::size_t n, bool complete, const std::string& name,
                  ImageInfo* info) {
  if (n == 0 && complete) fail(name, "empty file");
  switch (sniff(b, n)) {
    case Format::Png: return png_header(b, n, complete, name, info);
    case Format::Jpeg: return jpeg_header(b, n, complete, name, info);
    case Format::Bmp: return bmp_header(b, n, complete, name, info);
    case Format::Unknown: break;
  }
  if (!complete && n < 8) return false;
  fail(name, "unsupported image format (expected PNG, JPEG or BMP)");
}

// ---- containers: stage 2 ----------------------------------------------------------------

void check_png(const std::string& path, const std::uint8_t* b, std::size_t n) {
  std::size_t pos = 8;
  bool first = true;
  for (;;) {
    if (n - pos < 12)
      fail(path, "truncated PNG (file ends at byte " + std::to_string(n) + " before the IEND chunk)");
    std::uint32_t len = be32(b + pos);
    std::string name = chunk_name(b + pos + 4);
    if (len > 0x7FFFFFFFu) fail(path, "corrupt PNG (chunk '" + name + "' has an invalid length)");
    if (n - pos - 12 < len)
      fail(path, "truncated PNG (chunk '" + name + "' at byte " + std::to_string(pos) + " needs " +
                     std::to_string(len) + " bytes, file ends at byte " + std::to_string(n) + ")");
    if (first && name != "IHDR") fail(path, "corrupt PNG (first chunk is not IHDR)");
    first = false;
    std::uint32_t stored = be32(b + pos + 8 + len);
    if (crc32(b + pos + 4, len + 4) != stored)
      fail(path, "corrupt PNG (CRC mismatch in chunk '" + name + "' at byte " + std::to_string(pos) + ")");
    pos += 12 + std::size_t(len);
    if (name == "IEND") return;
  }
}

void check_jpeg(const std::string& path, const std::uint8_t* b, std::size_t n) {
  std::size_t pos = 2;  // after SOI
  bool seen_scan = false;
  for (;;) {
    // Junk between segments is skipped here; libjpeg then reports it ("extraneous
    // bytes before marker"), which is an error below.
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
    std::size_t len = be16(b + pos);
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
  fail(path, "truncated JPEG (file ends at byte " + std::to_string(n) + " before the end-of-image marker)");
}

// ---- channel conversion, as stb_image's stbi__convert_format(16) ----------------------

template <class T>
std::vector<T> convert_channels(std::vector<T> src, int n, int want, std::size_t pixels, T opaque) {
  if (want == 0 || want == n) return src;
  std::vector<T> dst(pixels * static_cast<std::size_t>(want));
  const T* s = src.data();
  T* d = dst.data();
  auto y = [](int r, int g, int b) { return static_cast<T>((r * 77 + g * 150 + b * 29) >> 8); };
  for (std::size_t i = 0; i < pixels; ++i, s += n, d += want) {
    switch (n * 8 + want) {
      case 1 * 8 + 2: d[0] = s[0]; d[1] = opaque; break;
      case 1 * 8 + 3: d[0] = d[1] = d[2] = s[0]; break;
      case 1 * 8 + 4: d[0] = d[1] = d[2] = s[0]; d[3] = opaque; break;
      case 2 * 8 + 1: d[0] = s[0]; break;
      case 2 * 8 + 3: d[0] = d[1] = d[2] = s[0]; break;
      case 2 * 8 + 4: d[0] = d[1] = d[2] = s[0]; d[3] = s[1]; break;
      case 3 * 8 + 1: d[0] = y(s[0], s[1], s[2]); break;
      case 3 * 8 + 2: d[0] = y(s[0], s[1], s[2]); d[1] = opaque; break;
      case 3 * 8 + 4: d[0] = s[0]; d[1] = s[1]; d[2] = s[2]; d[3] = opaque; break;
      case 4 * 8 + 1: d[0] = y(s[0], s[1], s[2]); break;
      case 4 * 8 + 2: d[0] = y(s[0], s[1], s[2]); d[1] = s[3]; break;
      case 4 * 8 + 3: d[0] = s[0]; d[1] = s[1]; d[2] = s[2]; break;
      default: break;
    }
  }
  return dst;
}

// ---- PNG (libpng) -------------------------------------------------------------------------
// The functions that call setjmp keep every object they touch after a longjmp in the
// job structure, and own no C++ objects with destructors.

struct PngJob {
  const std::uint8_t* data = nullptr;
  std::size_t size = 0, pos = 0;
  int expect_w = 0, expect_h = 0;
  png_structp png = nullptr;
  png_infop info = nullptr;
  std::vector<std::uint8_t> px8;     // 8-bit files
  std::vector<std::uint16_t> px16;   // 16-bit files, host byte order
  std::vector<png_bytep> rows;
  int channels = 0;
  char msg[256] = {0};
};

void png_fatal(png_structp png, png_const_charp msg) {
  auto* job = static_cast<PngJob*>(png_get_error_ptr(png));
  std::snprintf(job->msg, sizeof job->msg, "%s", msg ? msg : "error");
  png_longjmp(png, 1);
}
void png_ignore_warning(png_structp, png_const_charp) {}

void png_read_memory(png_structp png, png_bytep out, png_size_t n) {
  auto* job = static_cast<PngJob*>(png_get_io_ptr(png));
  if (job->size - job->pos < n) png_error(png, "unexpected end of data");
  std::memcpy(out, job->data + job->pos, n);
  job->pos += n;
}

bool png_decode(PngJob* job) {
  job->png = png_create_read_struct(PNG_LIBPNG_VER_STRING, job, png_fatal, png_ignore_warning);
  if (!job->png) {
    std::snprintf(job->msg, sizeof job->msg, "out of memory");
    return false;
  }
  job->info = png_create_info_struct(job->png);
  if (!job->info) {
    png_destroy_read_struct(&job->png, nullptr, nullptr);
    std::snprintf(job->msg, sizeof job->msg, "out of memory");
    return false;
  }
  if (setjmp(png_jmpbuf(job->png))) {
    png_destroy_read_struct(&job->png, &job->info, nullptr);
    return false;
  }
  // Our own limit (checked before) replaces libpng's 1,000,000-pixel-per-side default.
  png_set_user_limits(job->png, 0x7FFFFFFF, 0x7FFFFFFF);
  png_set_read_fn(job->png, job, png_read_memory);
  png_read_info(job->png, job->info);
  png_uint_32 w = 0, h = 0;
  int depth = 0, ctype = 0;
  png_get_IHDR(job->png, job->info, &w, &h, &depth, &ctype, nullptr, nullptr, nullptr);
  if (int(w) != job->expect_w || int(h) != job->expect_h) png_error(job->png, "inconsistent image header");
  // Native layout, as stb delivered it: palette -> RGB(A), low-depth gray -> 8 bits,
  // tRNS -> an alpha channel; 16-bit samples stay 16-bit (reduced later, after the
  // channel conversion, as stb did).
  if (ctype == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(job->png);
  if (ctype == PNG_COLOR_TYPE_GRAY && depth < 8) png_set_expand_gray_1_2_4_to_8(job->png);
  if (png_get_valid(job->png, job->info, PNG_INFO_tRNS)) png_set_tRNS_to_alpha(job->png);
#if __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  if (depth == 16) png_set_swap(job->png);
#endif
  png_set_interlace_handling(job->png);
  png_read_update_info(job->png, job->info);
  job->channels = png_get_channels(job->png, job->info);
  const std::size_t sample_bytes = depth == 16 ? 2 : 1;
  const std::size_t row_samples = std::size_t(w) * std::size_t(job->channels);
  if (png_get_rowbytes(job->png, job->info) != row_samples * sample_bytes)
    png_error(job->png, "unexpected row layout");
  bool no_memory = false;
  try {
    job->rows.resize(h);
    if (depth == 16) {
      job->px16.resize(row_samples * h);
      for (png_uint_32 r = 0; r < h; ++r) job->rows[r] = reinterpret_cast<png_bytep>(&job->px16[r * row_samples]);
    } else {
      job->px8.resize(row_samples * h);
      for (png_uint_32 r = 0; r < h; ++r) job->rows[r] = &job->px8[r * row_samples];
    }
  } catch (const std::bad_alloc&) {
    no_memory = true;
  }
  if (no_memory) png_error(job->png, "out of memory");
  png_read_image(job->png, job->rows.data());
  png_read_end(job->png, nullptr);
  png_destroy_read_struct(&job->png, &job->info, nullptr);
  return true;
}

Image decode_png(const std::string& name, const std::uint8_t* data, std::size_t size, const ImageInfo& info,
                 int want, bool keep_16bit) {
  PngJob job;
  job.data = data;
  job.size = size;
  job.expect_w = info.width;
  job.expect_h = info.height;
  if (!png_decode(&job)) fail(name, "cannot decode PNG: " + one_line(job.msg));
  const std::size_t pixels = std::size_t(info.width) * std::size_t(info.height);
  Image img;
  img.width = info.width;
  img.height = info.height;
  img.channels = want ? want : job.channels;
  if (info.bit_depth == 16) {
    std::vector<std::uint16_t> px = convert_channels<std::uint16_t>(std::move(job.px16), job.channels, want,
                                                                     pixels, 0xFFFF);
    if (keep_16bit) {
      img.bit_depth = 16;
      img.u16 = std::move(px);
    } else {
      img.u8.resize(px.size());
      for (std::size_t i = 0; i < px.size(); ++i) img.u8[i] = static_cast<std::uint8_t>(px[i] >> 8);
    }
  } else {
    img.u8 = convert_channels<std::uint8_t>(std::move(job.px8), job.channels, want, pixels, 0xFF);
  }
  return img;
}

// ---- JPEG (libjpeg-turbo) -----------------------------------------------------------------

struct JpegJob;
struct JpegErr {
  jpeg_error_mgr pub;  // first: libjpeg's pointer to it is a pointer to JpegErr
  JpegJob* job;
};

struct JpegJob {
  const std::uint8_t* data = nullptr;
  std::size_t size = 0;
  int want = 0, expect_w = 0, expect_h = 0;
  jpeg_decompress_struct cinfo;
  JpegErr err;
  jpeg_progress_mgr progress;
  std::jmp_buf jump;
  std::vector<std::uint8_t> px;
  int components = 0;
  bool cmyk = false;
  char msg[JMSG_LENGTH_MAX + 64] = {0};
};

JpegJob* job_of(j_common_ptr c) { return reinterpret_cast<JpegErr*>(c->err)->job; }

void jpeg_fatal(j_common_ptr c) {
  JpegJob* job = job_of(c);
  char text[JMSG_LENGTH_MAX];
  c->err->format_message(c, text);
  std::snprintf(job->msg, sizeof job->msg, "%s", text);
  std::longjmp(job->jump, 1);
}

// Warnings (level -1) are corrupt or missing data: errors here, so that damaged files
// are rejected instead of decoding to grey blocks. Trace messages (level >= 0) and the
// harmless metadata warnings are ignored; nothing is ever printed.
void jpeg_message(j_common_ptr c, int level) {
  if (level >= 0) return;
  int code = c->err->msg_code;
  if (code == JWRN_JFIF_MAJOR || code == JWRN_ADOBE_XFORM || code == JWRN_BOGUS_ICC) return;
  jpeg_fatal(c);
}

void jpeg_progress(j_common_ptr c) {
  auto* d = reinterpret_cast<j_decompress_ptr>(c);
  if (d->input_scan_number > kMaxJpegScans) {
    JpegJob* job = job_of(c);
    std::snprintf(job->msg, sizeof job->msg, "more than %d scans", kMaxJpegScans);
    std::longjmp(job->jump, 1);
  }
}

bool jpeg_decode(JpegJob* job) {
  job->err.job = job;
  job->cinfo.err = jpeg_std_error(&job->err.pub);
  job->err.pub.error_exit = jpeg_fatal;
  job->err.pub.emit_message = jpeg_message;
  if (setjmp(job->jump)) {
    jpeg_destroy_decompress(&job->cinfo);
    return false;
  }
  jpeg_create_decompress(&job->cinfo);
  job->progress.progress_monitor = jpeg_progress;
  job->cinfo.progress = &job->progress;
  jpeg_mem_src(&job->cinfo, job->data, static_cast<unsigned long>(job->size));
  jpeg_read_header(&job->cinfo, TRUE);
  if (int(job->cinfo.image_width) != job->expect_w || int(job->cinfo.image_height) != job->expect_h) {
    std::snprintf(job->msg, sizeof job->msg, "inconsistent image header");
    jpeg_destroy_decompress(&job->cinfo);
    return false;
  }
  // As stb: gray stays gray; YCbCr goes to RGB, or straight to its Y plane when gray
  // is wanted; CMYK/YCCK to CMYK, converted to RGB below.
  switch (job->cinfo.jpeg_color_space) {
    case JCS_GRAYSCALE: job->cinfo.out_color_space = JCS_GRAYSCALE; break;
    case JCS_YCbCr:
      job->cinfo.out_color_space = (job->want == 1 || job->want == 2) ? JCS_GRAYSCALE : JCS_RGB;
      break;
    case JCS_CMYK:
    case JCS_YCCK:
      job->cinfo.out_color_space = JCS_CMYK;
      job->cmyk = true;
      break;
    default: job->cinfo.out_color_space = JCS_RGB; break;
  }
  jpeg_start_decompress(&job->cinfo);
  job->components = job->cinfo.output_components;
  const std::size_t stride = std::size_t(job->cinfo.output_width) * std::size_t(job->components);
  bool no_memory = false;
  try {
    job->px.resize(stride * job->cinfo.output_height);
  } catch (const std::bad_alloc&) {
    no_memory = true;
  }
  if (no_memory) {
    std::snprintf(job->msg, sizeof job->msg, "out of memory");
    jpeg_destroy_decompress(&job->cinfo);
    return false;
  }
  while (job->cinfo.output_scanline < job->cinfo.output_height) {
    JSAMPROW row = job->px.data() + std::size_t(job->cinfo.output_scanline) * stride;
    jpeg_read_scanlines(&job->cinfo, &row, 1);
  }
  jpeg_finish_decompress(&job->cinfo);
  jpeg_destroy_decompress(&job->cinfo);
  return true;
}

Image decode_jpeg(const std::string& name, const std::uint8_t* data, std::size_t size, const ImageInfo& info,
                  int want) {
  auto job = std::make_unique<JpegJob>();
  job->data = data;
  job->size = size;
  job->want = want;
  job->expect_w = info.width;
  job->expect_h = info.height;
  if (!jpeg_decode(job.get())) fail(name, "cannot decode JPEG: " + one_line(job->msg));
  const std::size_t pixels = std::size_t(info.width) * std::size_t(info.height);
  int n = job->components;
  std::vector<std::uint8_t> px = std::move(job->px);
  if (job->cmyk) {
    // stb's conversion of (Adobe, inverted) CMYK: each of C, M, Y times K / 255.
    auto blinn = [](unsigned x, unsigned k) {
      unsigned t = x * k + 128;
      return static_cast<std::uint8_t>((t + (t >> 8)) >> 8);
    };
    std::vector<std::uint8_t> rgb(pixels * 3);
    for (std::size_t i = 0; i < pixels; ++i) {
      const std::uint8_t* s = &px[i * 4];
      rgb[i * 3 + 0] = blinn(s[0], s[3]);
      rgb[i * 3 + 1] = blinn(s[1], s[3]);
      rgb[i * 3 + 2] = blinn(s[2], s[3]);
    }
    px = std::move(rgb);
    n = 3;
  }
  Image img;
  img.width = info.width;
  img.height = info.height;
  img.channels = want ? want : n;
  img.u8 = convert_channels<std::uint8_t>(std::move(px), n, want, pixels, 0xFF);
  return img;
}

// ---- BMP (ours: uncompressed 24/32-bit only) --------------------------------------------

Image decode_bmp(const std::string& name, const std::uint8_t* b, std::size_t n, int want) {
  BmpLayout L;
  bmp_layout(b, n, true, name, &L);
  const std::uint64_t stride = ((std::uint64_t(L.width) * std::uint64_t(L.bpp) + 31) / 32) * 4;
  const std::uint64_t need = std::uint64_t(L.off_bits) + stride * std::uint64_t(L.height);
  if (need > n)
    fail(name, "truncated BMP (pixel data needs " + std::to_string(need) + " bytes, file has " +
                   std::to_string(n) + ")");
  const std::size_t pixels = std::size_t(L.width) * std::size_t(L.height);
  const int step = L.bpp / 8;
  std::vector<std::uint8_t> px(pixels * std::size_t(L.channels));
  bool any_alpha = false;
  for (int y = 0; y < L.height; ++y) {
    const std::uint8_t* row = b + L.off_bits + stride * std::uint64_t(L.top_down ? y : L.height - 1 - y);
    std::uint8_t* out = &px[std::size_t(y) * std::size_t(L.width) * std::size_t(L.channels)];
    for (int x = 0; x < L.width; ++x, row += step, out += L.channels) {
      out[0] = row[2];
      out[1] = row[1];
      out[2] = row[0];
      if (L.channels == 4) {
        out[3] = row[3];
        any_alpha |= row[3] != 0;
      }
    }
  }
  if (L.zero_alpha_is_opaque && !any_alpha)
    for (std::size_t i = 0; i < pixels; ++i) px[i * 4 + 3] = 0xFF;
  Image img;
  img.width = L.width;
  img.height = L.height;
  img.channels = want ? want : L.channels;
  img.u8 = convert_channels<std::uint8_t>(std::move(px), L.channels, want, pixels, 0xFF);
  return img;
}

// ---- PNG encoding (libpng) -----------------------------------------------------------------

struct PngOut {
  const std::uint8_t* pixels = nullptr;
  int width = 0, height = 0, channels = 0;
  png_structp png = nullptr;
  png_infop info = nullptr;
  std::vector<png_bytep> rows;
  std::vector<std::uint8_t> bytes;
  char msg[256] = {0};
};

void png_write_memory(png_structp png, png_bytep data, png_size_t n) {
  auto* out = static_cast<PngOut*>(png_get_io_ptr(png));
  bool no_memory = false;
  try {
    out->bytes.insert(out->bytes.end(), data, data + n);
  } catch (const std::bad_alloc&) {
    no_memory = true;
  }
  if (no_memory) png_error(png, "out of memory");
}
void png_flush_nothing(png_structp) {}

void png_fatal_out(png_structp png, png_const_charp msg) {
  auto* out = static_cast<PngOut*>(png_get_error_ptr(png));
  std::snprintf(out->msg, sizeof out->msg, "%s", msg ? msg : "error");
  png_longjmp(png, 1);
}

bool png_encode(PngOut* out) {
  out->png = png_create_write_struct(PNG_LIBPNG_VER_STRING, out, png_fatal_out, png_ignore_warning);
  if (!out->png) {
    std::snprintf(out->msg, sizeof out->msg, "out of memory");
    return false;
  }
  out->info = png_create_info_struct(out->png);
  if (!out->info) {
    png_destroy_write_struct(&out->png, nullptr);
    std::snprintf(out->msg, sizeof out->msg, "out of memory");
    return false;
  }
  if (setjmp(png_jmpbuf(out->png))) {
    png_destroy_write_struct(&out->png, &out->info);
    return false;
  }
  static const int types[5] = {0, PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA, PNG_COLOR_TYPE_RGB,
                               PNG_COLOR_TYPE_RGB_ALPHA};
  png_set_write_fn(out->png, out, png_write_memory, png_flush_nothing);
  png_set_IHDR(out->png, out->info, out->width, out->height, 8, types[out->channels], PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_set_compression_level(out->png, kPngLevel);
  png_set_filter(out->png, PNG_FILTER_TYPE_BASE, PNG_FILTER_SUB);
  png_write_info(out->png, out->info);
  png_write_image(out->png, out->rows.data());
  png_write_end(out->png, nullptr);
  png_destroy_write_struct(&out->png, &out->info);
  return true;
}

}  // namespace

// ---- public ---------------------------------------------------------------------------------

std::string megapixels_text(std::uint64_t pixels) {
  double v = double(pixels) / double(kMegapixel);
  char buf[32];
  std::snprintf(buf, sizeof buf, v >= 100 ? "%.0f" : "%.3g", v);
  return buf;
}

bool parse_max_pixels(const std::string& text, std::uint64_t* pixels) {
  if (text.empty()) return false;
  char* end = nullptr;
  errno = 0;
  double v = std::strtod(text.c_str(), &end);
  if (errno != 0 || end != text.c_str() + text.size() || !std::isfinite(v) || v <= 0 ||
      v > double(kMegapixel))  // at most 2^20 Mpx (2^40 pixels)
    return false;
  double px = std::round(v * double(kMegapixel));
  if (px < 1) return false;
  *pixels = static_cast<std::uint64_t>(px);
  return true;
}

void check_limits(const ImageInfo& info, const std::string& name, const DecodeLimits& limits) {
  const std::uint64_t pixels = std::uint64_t(info.width) * std::uint64_t(info.height);
  if (pixels > limits.max_pixels)
    fail(name, "image is " + std::to_string(info.width) + "x" + std::to_string(info.height) + " (" +
                   megapixels_text(pixels) + " Mpx), above the limit of " + megapixels_text(limits.max_pixels) +
                   " Mpx (raise it with --max-pixels)");
}

ImageInfo probe(const std::uint8_t* data, std::size_t size, const std::string& name) {
  ImageInfo info;
  parse_header(data, data ? size : 0, true, name, &info);
  return info;
}

ImageInfo probe(const std::string& path) {
  std::uint64_t size = 0;
  Fd f{open_regular(path, &size)};
  std::vector<std::uint8_t> bytes;
  std::size_t chunk = 64 * 1024;
  ImageInfo info;
  for (;;) {
    bool more = read_more(f.fd, path, &bytes, chunk);
    if (parse_header(bytes.data(), bytes.size(), !more, path, &info)) return info;
    if (bytes.size() >= kMaxFileBytes) fail(path, "no image header in the first 1 GiB");
    chunk = std::min<std::size_t>(chunk * 4, kMaxFileBytes - bytes.size());
  }
}

Image decode(const std::uint8_t* data, std::size_t size, const std::string& name, int want_channels,
             bool keep_16bit, const DecodeLimits& limits) {
  if (want_channels < 0 || want_channels > 4)
    fail(name, "invalid channel count requested (" + std::to_string(want_channels) + ")");
  if (!data || size == 0) fail(name, "empty file");
  if (size > kMaxFileBytes) fail(name, "file too large (" + std::to_string(size) + " bytes)");
  ImageInfo info;
  parse_header(data, size, true, name, &info);  // stage 1
  check_limits(info, name, limits);
  try {
    switch (sniff(data, size)) {  // stage 2, then 3
      case Format::Png:
        check_png(name, data, size);
        return decode_png(name, data, size, info, want_channels, keep_16bit);
      case Format::Jpeg:
        check_jpeg(name, data, size);
        return decode_jpeg(name, data, size, info, want_channels);
      case Format::Bmp: return decode_bmp(name, data, size, want_channels);
      case Format::Unknown: break;
    }
  } catch (const std::bad_alloc&) {
    fail(name, "out of memory decoding a " + std::to_string(info.width) + "x" + std::to_string(info.height) +
                   " image");
  }
  fail(name, "unsupported image format (expected PNG, JPEG or BMP)");
}

std::vector<std::uint8_t> read_image_file(const std::string& path) { return read_whole_file(path); }

Image load(const std::string& path, int want_channels, bool keep_16bit, const DecodeLimits& limits) {
  if (want_channels < 0 || want_channels > 4)
    fail(path, "invalid channel count requested (" + std::to_string(want_channels) + ")");
  std::vector<std::uint8_t> bytes = read_whole_file(path);
  return decode(bytes.data(), bytes.size(), path, want_channels, keep_16bit, limits);
}

std::vector<std::uint8_t> encode_png(const std::uint8_t* pixels, int width, int height, int channels) {
  if (!pixels) throw Error("encode_png: no pixel data");
  if (width <= 0 || height <= 0 || channels < 1 || channels > 4)
    throw Error("encode_png: invalid image shape " + std::to_string(width) + "x" + std::to_string(height) + "x" +
                std::to_string(channels));
  if (std::uint64_t(width) * channels * height > kMaxFileBytes * 4ull) throw Error("encode_png: image too large");
  auto out = std::make_unique<PngOut>();
  out->pixels = pixels;
  out->width = width;
  out->height = height;
  out->channels = channels;
  const std::size_t stride = std::size_t(width) * std::size_t(channels);
  out->rows.resize(std::size_t(height));
  for (int y = 0; y < height; ++y)
    out->rows[std::size_t(y)] = const_cast<png_bytep>(pixels + std::size_t(y) * stride);  // libpng only reads them
  out->bytes.reserve(stride * std::size_t(height) / 2 + 1024);
  if (!png_encode(out.get())) throw Error("encode_png: " + one_line(out->msg));
  return std::move(out->bytes);
}

void save_png(const std::string& path, const std::uint8_t* pixels, int width, int height, int channels) {
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
