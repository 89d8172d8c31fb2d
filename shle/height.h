// Stage 2 of SHLE: the height of a device from one disparity map and its box,
// exactly as the released code computes it by default:
//   1. extend the box extend_top px up and extend_bottom px down, clip it to the
//      map, take rows int(y0)..int(y1)-1 and columns int(x0)..int(x1)-1;
//   2. back-project every pixel with a valid disparity (Z = bf / d) and keep the
//      points with height above the road H > min_height (the released `--M`);
//      for a level camera the road-frame Y = (v - cy) Z / fy - mount_height, H = -Y;
//   3. centre depth = mode of a Gaussian KDE of their depths (bandwidth 2.5 m) on
//      the grid 0, step, ..., first maximum (geometry/kde.h); or their mean depth
//      without the KDE;
//   4. keep the points with centre - sigma < Z < centre + sigma (open interval);
//   5. height = |mean Y| of the lowest_n lowest of them (largest Y), all if fewer.
// An empty window, no valid point or a box off the map give no height (the
// released code's NaN), with the reason in `problem`.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "geometry/kde.h"
#include "shle/calibration.h"
#include "shle/types.h"

namespace shle {

struct HeightOptions {
  double extend_top = 20, extend_bottom = 20;  // released extend_num, both edges
  double min_height = 1.5;                     // released --M prefilter, metres
  bool use_kde = true;                         // false: centre = mean depth (--no_Gaussian)
  double bandwidth = 2.5;                      // metres, sklearn absolute bandwidth
  double grid_step = 1.0;                      // metres; finer is a documented deviation
  bool use_depth_window = true;                // false: keep all points (--no_depth_filter)
  double sigma = 0.6;                          // half width of the open depth window, metres
  int lowest_n = 10;
};

// Documented limits. The KDE grid step bounds the grid's length (depth / step
// points, at most 2^26: geometry::kMaxKdeGridPoints); the preallocated scratch
// covers boxes up to 4 Mpx and grows on demand beyond (a calibrated size commits
// no memory by itself).
constexpr double kMinGridStep = 1e-3, kMaxGridStep = 1e3;  // metres
constexpr std::size_t kPreallocatedPixels = std::size_t(4) << 20;

// Throws shle::Error naming the first option out of range.
void validate(const HeightOptions& options);

struct HeightResult {
  Box window;            // the box after extension and clipping
  int u0 = 0, u1 = 0;    // columns [u0, u1)
  int v0 = 0, v1 = 0;    // rows [v0, v1)
  std::size_t valid = 0;           // pixels with a valid disparity
  std::size_t points = 0;          // ... that pass the height prefilter (the KDE input)
  std::size_t window_points = 0;   // ... inside the depth window
  double centre_depth = 0;         // KDE mode (or mean depth); meaningful if points > 0
  bool has_height = false;
  double height = 0;               // metres above the road
  std::string problem;             // why there is no height
};

// Extension and clipping of step 1, in the released arithmetic.
Box extend_and_clip(const Box& box, double extend_top, double extend_bottom, int width, int height);

class HeightEstimator {
 public:
  HeightEstimator(const Calibration& calibration, const HeightOptions& options);
  // Deterministic; keeps its scratch buffers between calls (not thread-safe:
  // use one estimator per thread).
  HeightResult estimate(const DisparityMap& disparity, const Box& box);

  const HeightOptions& options() const { return opt_; }

 private:
  void group_depths(std::size_t n);

  Calibration cal_;
  HeightOptions opt_;
  // Scratch: per point depth and road Y; the distinct depths with their counts
  // and the open-addressing table that finds them.
  struct Point {
    double z, y;
  };
  std::vector<Point> pts_;
  struct Slot {
    std::uint64_t key;  // depth bit pattern, 0 = empty
    std::uint64_t count;
  };
  std::vector<Slot> slots_;
  std::vector<std::uint32_t> used_slots_;
  std::vector<std::pair<double, std::uint32_t>> distinct_;
  std::vector<double> kde_z_, kde_w_, lowest_, row_z_, row_y_;
  std::vector<std::int64_t> row_keep_;  // per pixel: bit 0 valid, bit 1 kept
};

}  // namespace shle
