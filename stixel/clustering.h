// Object grouping on top of the Stixel World (pyStixel-lib's
// attach_dbscan_clustering and derive_3d_bounding_boxes_from_clusters).
#pragma once

#include <array>
#include <vector>

#include "stixel/dbscan.h"
#include "stixel/projection.h"
#include "stixel/world.h"

namespace stixel {

struct ClusterOptions {
  double eps = 1.42;    // metres
  int min_samples = 2;  // neighbours incl. the point itself
  // The two axes of the stixel top points DBSCAN sees. (0, 2) = x/z, right for
  // optical-frame calibrations (standard K, T = I; pyStixel-lib since 2026-04);
  // (0, 1) = x/y for Waymo vehicle-frame calibrations (K_eff, T = inv(extrinsic)).
  int axis_a = 0, axis_b = 2;
};

// The two chosen axes of each point (the bird's-eye view DBSCAN and the BEV
// picture work in). Throws Error unless the axes are two different of 0, 1, 2.
std::vector<Point2> bev_coordinates(const std::vector<Point3>& points, int axis_a, int axis_b);

// Clusters the stixels' top points: sets every stixel's `cluster` (-1 = noise)
// and context.clusters to the maximum label (-1 when there is no cluster).
// `top` must be top_points(world, ...) of this world.
void cluster_stixels(StixelWorld& world, const std::vector<Point3>& top,
                     const ClusterOptions& options);
void cluster_stixels(StixelWorld& world, const Projection& projection,
                     const ClusterOptions& options);

struct Box3D {
  // Axis-aligned box: (x0,y0,z0), (x1,y0,z0), (x1,y1,z0), (x0,y1,z0), then the
  // same four with z1 (pyStixel-lib's corner order).
  std::array<std::array<float, 3>, 8> corners{};
  int cluster_id = 0;
  int num_stixels = 0;
  float confidence = 0;  // mean stixel confidence
};

// The 12 corner-index pairs that draw a box's edges.
extern const int kBoxEdges[12][2];

// One box per cluster id with >= min_cluster_size stixels, enclosing the 3D top
// and bottom points of its stixels; sorted by cluster id. Noise (-1) is a
// cluster of its own only if include_noise.
std::vector<Box3D> boxes_from_clusters(const StixelWorld& world, const Projection& projection,
                                       int min_cluster_size = 2, bool include_noise = false);

}  // namespace stixel
