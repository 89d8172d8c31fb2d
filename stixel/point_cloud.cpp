#include "stixel/point_cloud.h"

#include <algorithm>
#include <charconv>
#include <cstring>

#include "stixel/decimal_text.h"
#include "stixel/error.h"

namespace stixel {
namespace {

void put_u32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int k = 0; k < 4; ++k) out.push_back(static_cast<std::uint8_t>(v >> (8 * k)));  // little-endian on any host
}

void put_f32(std::vector<std::uint8_t>& out, float f) {
  std::uint32_t bits;
  std::memcpy(&bits, &f, 4);
  put_u32(out, bits);
}


}  // namespace

PointCloud world_point_cloud(const StixelWorld& world, const Projection& projection, const PointCloudOptions& o) {
  const RgbImage* img = o.image;
  if (img && (img->width < 1 || img->height < 1 ||
              img->pixels.size() != static_cast<std::size_t>(img->width) * img->height * 3))
    throw Error("point cloud: the image is not width * height * 3 bytes");
  PointCloud c;
  std::vector<int> owner;
  c.xyz = point_cloud(world, projection, &owner);
  c.stixel.assign(owner.begin(), owner.end());
  const bool by_cluster = !img && world.context.clusters > 0;
  if (img || by_cluster) c.color.resize(c.xyz.size());
  if (o.cluster_labels) c.cluster.resize(c.xyz.size());
  // point_cloud() emits rows vT..vB-1 of each stixel in order: walk them again.
  std::size_t k = 0;
  for (std::size_t i = 0; i < world.stixels.size(); ++i) {
    const Stixel& s = world.stixels[i];
    for (std::int64_t v = s.vT; v < s.vB; ++v, ++k) {
      if (img) {
        const std::int64_t x = std::clamp<std::int64_t>(s.u, 0, img->width - 1);
        const std::int64_t y = std::clamp<std::int64_t>(v, 0, img->height - 1);
        const std::uint8_t* p = &img->pixels[(static_cast<std::size_t>(y) * img->width + x) * 3];
        c.color[k] = {p[0], p[1], p[2]};
      } else if (by_cluster) {
        c.color[k] = cluster_color(s.cluster, world.context.clusters);
      }
      if (o.cluster_labels) c.cluster[k] = s.cluster;
    }
  }
  return c;
}

std::vector<std::uint8_t> to_ply(const PointCloud& c, const std::string& comment) {
  std::string header = "ply\nformat binary_little_endian 1.0\n";
  if (!comment.empty()) {
    header += "comment ";
    for (char ch : comment) header += (static_cast<unsigned char>(ch) < 0x20 || ch == 0x7f) ? ' ' : ch;
    header += "\n";
  }
  header += "element vertex " + std::to_string(c.xyz.size()) + "\n";
  header += "property float x\nproperty float y\nproperty float z\n";
  const bool rgb = !c.color.empty(), labels = !c.cluster.empty();
  if (rgb) header += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  header += "property int stixel\n";
  if (labels) header += "property int cluster\n";
  header += "end_header\n";
  std::vector<std::uint8_t> out(header.begin(), header.end());
  out.reserve(out.size() + c.xyz.size() * (12 + (rgb ? 3 : 0) + 4 + (labels ? 4 : 0)));
  for (std::size_t i = 0; i < c.xyz.size(); ++i) {
    put_f32(out, static_cast<float>(c.xyz[i].x));
    put_f32(out, static_cast<float>(c.xyz[i].y));
    put_f32(out, static_cast<float>(c.xyz[i].z));
    if (rgb) out.insert(out.end(), c.color[i].begin(), c.color[i].end());
    put_u32(out, static_cast<std::uint32_t>(c.stixel[i]));
    if (labels) put_u32(out, static_cast<std::uint32_t>(c.cluster[i]));
  }
  return out;
}

std::string to_points_csv(const PointCloud& c) {
  const bool rgb = !c.color.empty(), labels = !c.cluster.empty();
  std::string out = rgb ? "x,y,z,r,g,b,stixel" : "x,y,z,stixel";
  if (labels) out += ",cluster";
  out += "\n";
  for (std::size_t i = 0; i < c.xyz.size(); ++i) {
    for (int a = 0; a < 3; ++a) {
      append_float(out, static_cast<float>(c.xyz[i][a]));
      out += ',';
    }
    if (rgb)
      for (int k = 0; k < 3; ++k) {
        append_int(out, c.color[i][k]);
        out += ',';
      }
    append_int(out, c.stixel[i]);
    if (labels) {
      out += ',';
      append_int(out, c.cluster[i]);
    }
    out += '\n';
  }
  return out;
}

}  // namespace stixel
