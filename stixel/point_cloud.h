// A Stixel World as a 3D point cloud, the points pyStixel-lib's
// convert_to_point_cloud(world) returns (ref §4.2): one point per image row v in
// [vT, vB) of every stixel (none if vB <= vT), in stixel order, all at the
// stixel's u, X = inverse(K4 * T) * [u*d, v*d, d, 1] (projection.h), plus what a
// viewer wants beside them: the owning stixel's index, its cluster label and a
// colour. Written as binary little-endian PLY or CSV (the apps' --points).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "stixel/colormap.h"
#include "stixel/projection.h"
#include "stixel/render.h"
#include "stixel/world.h"

namespace stixel {

struct PointCloud {
  std::vector<Point3> xyz;
  std::vector<std::int32_t> stixel;   // index into world.stixels of every point
  std::vector<Rgb> color;             // empty: no colour
  std::vector<std::int32_t> cluster;  // empty: no cluster labels
};

struct PointCloudOptions {
  // Colour of every point: the pixel at (u, v) of this image (the one the
  // stixels' rows refer to, i.e. the network-size image), as pyStixel-lib's
  // return_rgb_values=True reads the embedded image; rows or columns outside it
  // take the nearest edge pixel (where pyStixel-lib would raise IndexError).
  // Without an image but with clusters (context.clusters > 0) the colour is
  // jet(cluster / context.clusters), as pyStixel-lib colours clustered worlds.
  const RgbImage* image = nullptr;
  bool cluster_labels = false;  // carry each point's stixel cluster label
};

// Throws Error if the image is not width * height * 3 bytes.
PointCloud world_point_cloud(const StixelWorld& world, const Projection& projection,
                             const PointCloudOptions& options = {});

// Binary little-endian PLY: vertex x, y, z (float32), then red, green, blue
// (uchar) if coloured, stixel (int32), cluster (int32) if labelled.
// `comment` (one line, no control characters) goes into the header.
std::vector<std::uint8_t> to_ply(const PointCloud& cloud, const std::string& comment = "");

// CSV with header x,y,z[,r,g,b],stixel[,cluster]; coordinates in the shortest
// text that reads back as the same float32 the PLY holds.
std::string to_points_csv(const PointCloud& cloud);

}  // namespace stixel
