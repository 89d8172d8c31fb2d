// Evaluation metrics of the SHLE paper.
//   HE  = estimate - truth (metres), HER = HE / truth; their absolute companions
//   (the released code reports the signed forms only).
//   CPD   = Euclidean distance between the centres of predicted and true box (px)
//   RCPDA = CPD / (w_gt * h_gt),  RCPDH = CPD / sqrt(w_gt^2 + h_gt^2)
#pragma once

#include <cstddef>
#include <vector>

#include "shle/types.h"

namespace shle {

struct HeightError {
  double he = 0, her = 0, he_abs = 0, her_abs = 0;
};

// Throws shle::Error unless truth > 0 and both are finite.
HeightError height_error(double estimate, double truth);

// Means over the estimates of HE, HER, |HE|, |HER| (n = 0: all zero).
struct HeightErrorSummary {
  std::size_t n = 0;
  HeightError mean;
};
HeightErrorSummary summarize_height_errors(const std::vector<double>& estimates, double truth);

struct CentreDistance {
  double cpd = 0, rcpda = 0, rcpdh = 0;
};

// False (and *out untouched) when the true box has no area or a box is not finite.
bool centre_distance(const Box& predicted, const Box& truth, CentreDistance* out);

}  // namespace shle
