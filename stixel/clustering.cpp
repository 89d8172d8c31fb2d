#include "stixel/clustering.h"

#include <algorithm>
#include <map>
#include <string>

#include "stixel/error.h"

namespace stixel {

const int kBoxEdges[12][2] = {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {4, 5}, {5, 6},
                              {6, 7}, {7, 4}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};

std::vector<Point2> bev_coordinates(const std::vector<Point3>& points, int axis_a, int axis_b) {
  if (axis_a < 0 || axis_a > 2 || axis_b < 0 || axis_b > 2 || axis_a == axis_b)
    throw Error("bird's-eye view: axes must be two different values of 0 (x), 1 (y), 2 (z), got " +
                std::to_string(axis_a) + " and " + std::to_string(axis_b));
  std::vector<Point2> bev;
  bev.reserve(points.size());
  for (const Point3& p : points) bev.push_back({p[axis_a], p[axis_b]});
  return bev;
}

void cluster_stixels(StixelWorld& world, const std::vector<Point3>& top,
                     const ClusterOptions& o) {
  if (top.size() != world.stixels.size())
    throw Error("clustering: " + std::to_string(top.size()) + " top points for " +
                std::to_string(world.stixels.size()) + " stixels");
  const std::vector<int> labels = dbscan(bev_coordinates(top, o.axis_a, o.axis_b), o.eps, o.min_samples);
  int max_label = -1;
  for (std::size_t i = 0; i < labels.size(); ++i) {
    world.stixels[i].cluster = labels[i];
    max_label = std::max(max_label, labels[i]);
  }
  world.context.clusters = max_label;
}

void cluster_stixels(StixelWorld& world, const Projection& projection, const ClusterOptions& o) {
  cluster_stixels(world, top_points(world, projection), o);
}

std::vector<Box3D> boxes_from_clusters(const StixelWorld& world, const Projection& projection,
                                       int min_cluster_size, bool include_noise) {
  struct Acc {
    Point3 lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
    int count = 0;
    double confidence = 0;
  };
  std::map<int, Acc> acc;  // ordered by cluster id
  for (const Stixel& s : world.stixels) {
    if (s.cluster < 0 && !include_noise) continue;
    Acc& a = acc[s.cluster];
    for (const Point3& p : {projection.point(s.u, s.vT, s.d), projection.point(s.u, s.vB, s.d)}) {
      a.lo = {std::min(a.lo.x, p.x), std::min(a.lo.y, p.y), std::min(a.lo.z, p.z)};
      a.hi = {std::max(a.hi.x, p.x), std::max(a.hi.y, p.y), std::max(a.hi.z, p.z)};
    }
    ++a.count;
    a.confidence += s.confidence;
  }
  std::vector<Box3D> boxes;
  for (const auto& [id, a] : acc) {
    if (a.count < min_cluster_size) continue;
    const float x0 = static_cast<float>(a.lo.x), y0 = static_cast<float>(a.lo.y),
                z0 = static_cast<float>(a.lo.z);
    const float x1 = static_cast<float>(a.hi.x), y1 = static_cast<float>(a.hi.y),
                z1 = static_cast<float>(a.hi.z);
    Box3D b;
    b.corners = {{{x0, y0, z0}, {x1, y0, z0}, {x1, y1, z0}, {x0, y1, z0},
                  {x0, y0, z1}, {x1, y0, z1}, {x1, y1, z1}, {x0, y1, z1}}};
    b.cluster_id = id;
    b.num_stixels = a.count;
    b.confidence = static_cast<float>(a.confidence / a.count);
    boxes.push_back(b);
  }
  return boxes;
}

}  // namespace stixel
