// Mode of a one-dimensional Gaussian kernel density estimate on a regular grid,
// as the released SHLE code finds the bar's depth: sklearn KernelDensity with a
// Gaussian kernel of absolute bandwidth h (the kernel's standard deviation, in
// data units), scored at the grid points 0, s, 2s, ..., floor(max/s) s, and the
// first grid point of maximal density taken as the mode.
//
// Exactness. The log of the normalisation constant is the same at every grid
// point, so the argmax is that of S(g) = sum_k w_k exp(-(g - z_k)^2 / (2 h^2)).
// S is evaluated directly in double precision; the only terms left out are those
// with |g - z_k| > T, T^2 = s^2 + 2 h^2 ln(2^60 W / w_max) (W the total weight):
// together they are below 2^-60 of the density at the mode (some grid point lies
// within s of the heaviest sample), i.e. below the rounding error of the sum
// itself. Grid points with no sample within T are never the mode and are
// skipped. The result is therefore the argmax of the full evaluation, not an
// approximation, while the work is O(m (2T/s + 1)) for m distinct samples
// instead of O(n * grid length): the grid may reach 7681 points for a 1/32 px
// disparity with bf = 240.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace geometry {

struct KdeOptions {
  double bandwidth = 2.5;  // kernel standard deviation, data units (metres)
  double grid_step = 1.0;  // the released code's integer-metre grid
};

struct KdeMode {
  double mode = 0;              // grid position of the first maximum: index * grid_step
  std::int64_t grid_index = 0;  // index on the grid 0, s, 2s, ...
  double density = 0;           // S(mode), the unnormalised kernel sum
};

// Samples sorted ascending (repeats allowed), finite and >= 0, each with a weight
// > 0 (a count of identical samples). Throws geometry::Error for an empty set,
// unsorted, negative or non-finite samples, non-positive weights, a bandwidth or
// grid step that is not a positive finite number, or a grid of more than
// kMaxKdeGridPoints points (largest sample / grid step), which bounds the time.
constexpr double kMaxKdeGridPoints = 67108864.0;  // 2^26

KdeMode gaussian_kde_mode(const double* sorted_values, const double* weights, std::size_t n,
                          const KdeOptions& options);

// Unweighted samples in any order: sorts, merges equal values into weights and
// calls the function above.
KdeMode gaussian_kde_mode(std::vector<double> samples, const KdeOptions& options);

// sklearn's KernelDensity.score_samples at x for the weighted samples: the log of
// the weighted mean of the normalised Gaussian kernels, evaluated in full with a
// log-sum-exp. O(n); for tests and diagnostics.
double gaussian_kde_log_density(const double* values, const double* weights, std::size_t n,
                                double x, double bandwidth);

}  // namespace geometry
