// Image files for the apps: PNG through libpng, JPEG through libjpeg-turbo (libjpeg
// API), uncompressed 24/32-bit BMP through a small reader of our own. The runtime
// libraries never touch image files. Errors are json-free one-liners naming the path.
//
// Untrusted input: a file is refused before any pixel memory is allocated when its
// header declares more than DecodeLimits::max_pixels; truncated or corrupt files
// (bad PNG CRCs, JPEG data ending before EOI, libjpeg's "corrupt data" warnings, BMP
// pixel arrays cut short) are errors, never half-grey images.
#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace imageio {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& what) : std::runtime_error(what) {}
};

struct Image {
  int width = 0, height = 0, channels = 0;  // channels: 1 gray, 2 gray+alpha, 3 RGB, 4 RGBA
  int bit_depth = 8;                        // 8 or 16
  std::vector<std::uint8_t> u8;             // bit_depth 8: row-major, interleaved
  std::vector<std::uint16_t> u16;           // bit_depth 16 (e.g. disparity PNGs)
};

// 1 Mpx = 2^20 pixels throughout (messages, --max-pixels).
constexpr std::uint64_t kMegapixel = 1ull << 20;

struct DecodeLimits {
  // width * height above this is refused from the header, before decoding.
  std::uint64_t max_pixels = 64 * kMegapixel;
};

// What a file's header says, without decoding pixels.
struct ImageInfo {
  std::string format;  // "PNG", "JPEG" or "BMP"
  int width = 0, height = 0;
  int channels = 0;   // as load(path, 0) returns them (PNG palette/tRNS expanded)
  int bit_depth = 8;  // bits per stored sample: PNG 1/2/4/8/16, JPEG 8, BMP 8
};

// Loads PNG/JPEG/BMP. want_channels: 0 = as stored, else converted to 1..4 the way
// stb_image did (gray -> RGB replicates; RGB -> gray is (77 R + 150 G + 29 B) >> 8;
// alpha is dropped, never composited; added alpha is opaque). keep_16bit: keep
// 16-bit PNG samples in u16 instead of reducing them to their high byte.
Image load(const std::string& path, int want_channels = 0, bool keep_16bit = false,
           const DecodeLimits& limits = {});

// The same on bytes in memory; `name` stands for the path in messages.
Image decode(const std::uint8_t* data, std::size_t size, const std::string& name,
             int want_channels, bool keep_16bit, const DecodeLimits& limits);

// The file's bytes, read as load() reads them (regular files only, size limit):
// for a caller that needs both the pixels (decode) and the encoded file.
std::vector<std::uint8_t> read_image_file(const std::string& path);

// The header only (reads the first bytes of the file, more only for JPEGs with large
// metadata before the frame header). Throws Error("path: problem").
ImageInfo probe(const std::string& path);
ImageInfo probe(const std::uint8_t* data, std::size_t size, const std::string& name);

// Throws Error("name: image is WxH (N Mpx), above the limit of M Mpx (raise it with
// --max-pixels)") when info exceeds the limit.
void check_limits(const ImageInfo& info, const std::string& name, const DecodeLimits& limits);

// "64", "0.5", "9537": megapixels for messages.
std::string megapixels_text(std::uint64_t pixels);

// Parses a --max-pixels value: megapixels as a positive number ("64", "0.5", "200").
// False when the text is not one.
bool parse_max_pixels(const std::string& text, std::uint64_t* pixels);

// Encodes 8-bit interleaved pixels (1..4 channels) as PNG bytes (libpng, fast zlib level).
std::vector<std::uint8_t> encode_png(const std::uint8_t* pixels, int width, int height,
                                     int channels);

// Writes a PNG atomically (outputs::write_file: temporary file, then rename); never
// leaves a partial file. Sets of files: encode_png and outputs::FileSet.
void save_png(const std::string& path, const std::uint8_t* pixels, int width, int height,
              int channels);

}  // namespace imageio
