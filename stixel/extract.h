// Prediction tensor -> Stixel World ("revert" in the reference code).
//
// The prediction of one image is [A, N, U] float32, contiguous, attribute-major:
//   A = 3 (head variants V0-V3): vB, vT, P
//   A = 4 (V4, latest):          vB, vT, d_res, P
// N candidates (depth anchors) per column, U columns.
#pragma once

#include "stixel/anchors.h"
#include "stixel/world.h"

namespace stixel {

struct ExtractOptions {
  // A candidate becomes a stixel if P >= threshold, compared in double like the
  // reference (numpy float32 scalar against a Python float). 0 keeps every
  // candidate with a non-NaN P, as the V4 reference does.
  double threshold = 0.36;
  int image_height = 1280;  // H in v = int(v_hat * H + 1)
  int stixel_width = 8;     // column pitch: u = column * stixel_width, width = stixel_width
  // Multiplies every depth; camera_depth_scale() gives f_camera / f_train for
  // focal-length adaptation. 1 = the depths exactly as the network predicts them.
  double depth_scale = 1.0;
};

// The authors' depth decoding of a V4 candidate (StixelNExT_Pro
// _decode_depth_residual): exp(log(max(anchor, 1e-6)) + d_res), all in double
// from the float64 anchor, as numpy computes it. Rounded to float it equals the
// reference's d bit for bit (a test compares on recorded network outputs).
double decode_depth_residual(double anchor, float d_res);

// Walks columns u (outer) and candidates n (inner), the reference's output order.
// Emits u = column * width, vT = int(vT_hat * H + 1), vB = int(vB_hat * H + 1),
// d = anchor_n (A = 3) or decode_depth_residual(anchor_n, d_res) (A = 4) with the
// anchors' double values (Anchors::exact_at), times depth_scale, confidence = P, width; label, idx and cluster stay 0. The rows are
// computed exactly (the float32 value times the integer H, plus 1, in double: no
// rounding), as the reference's numpy code does, then truncated toward zero.
// Throws Error for invalid shapes/options and for a non-finite vT, vB or d_res
// of a kept candidate. Only the stixels are filled; the context is the caller's.
StixelWorld extract(const float* prediction, int attrs, int candidates, int columns,
                    const Anchors& anchors, const ExtractOptions& options);

// The same, appending to `out` (whose context is left untouched).
void extract_into(StixelWorld& out, const float* prediction, int attrs, int candidates,
                  int columns, const Anchors& anchors, const ExtractOptions& options);

}  // namespace stixel
