/* roadnn testing helpers, C API (C99): compare an output of yours with a tensor of a
 * reference safetensors file (e.g. written by PyTorch or scripts/torch_dump.py) under a
 * tolerance, and get the worst element and its coordinates. The C++ wrapper for unit
 * tests is roadnn/testing.hpp. Same rule as the nncompare program (docs/NUMERICS.md):
 *
 *   element i fails when |data_i - ref_i| > atol + rtol * scale,
 *   scale = max |ref| over the tensor (default) or |ref_i| (per_element = 1);
 *   NaN matches NaN and an infinity the same infinity; any other non-finite element fails.
 */
#ifndef ROADNN_TESTING_H
#define ROADNN_TESTING_H

#include <stddef.h>
#include <stdint.h>

#include "roadnn/roadnn.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct roadnn_tolerance {
  double atol;     /* absolute part, >= 0 (default 0) */
  double rtol;     /* relative part, >= 0 (default 1e-4) */
  int per_element; /* 0: rtol scales max|ref| of the tensor; 1: |ref_i| */
} roadnn_tolerance;

#define ROADNN_COMPARE_MAX_RANK 8

typedef struct roadnn_compare_result {
  int ok;                /* 1: same shape and every element within tolerance */
  int shape_matches;     /* 0: the values were not compared */
  int64_t count;         /* elements compared */
  int64_t failing;       /* elements out of tolerance */
  double max_abs_diff;   /* +inf when an element is non-finite on one side only */
  double max_abs_ref;    /* over the finite reference values */
  double max_rel_diff;   /* max_abs_diff / max_abs_ref */
  double mean_abs_diff;
  double allowed;        /* atol + rtol * max_abs_ref */
  size_t rank;
  int64_t worst[ROADNN_COMPARE_MAX_RANK]; /* coordinates of the largest difference */
  double worst_value, worst_ref;
  int64_t nan_count, inf_count, ref_nan_count, ref_inf_count;
  /* One line for a test log: the tensor, its shape, the statistics above, the worst
   * element's coordinates and both values. */
  char message[512];
} roadnn_compare_result;

ROADNN_API roadnn_tolerance roadnn_tolerance_default(void);

/* Compares `data` (row-major, `rank` dimensions `shape`, numel(shape) floats) with the
 * tensor `tensor_name` of the safetensors file `reference_path` (F32, F16 or BF16).
 * ROADNN_OK with out->ok = 0 for a shape mismatch or values out of tolerance (the
 * message says which); ROADNN_ERROR_IO when the file cannot be opened;
 * ROADNN_ERROR_INVALID_ARGUMENT for a null argument, a malformed file, a missing or
 * non-float tensor, a negative tolerance or a rank above ROADNN_COMPARE_MAX_RANK.
 * `tolerance` may be NULL (the default). */
ROADNN_API roadnn_status roadnn_compare_with_reference(const float* data, const int64_t* shape, size_t rank,
                                                      const char* reference_path, const char* tensor_name,
                                                      const roadnn_tolerance* tolerance,
                                                      roadnn_compare_result* out);

#ifdef __cplusplus
}
#endif

#endif /* ROADNN_TESTING_H */
