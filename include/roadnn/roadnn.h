/* roadnn: road-scene CNNs on ordinary CPUs, exactly as PyTorch computes them.
 *
 * The C API (C99). A model is loaded once and is immutable: its packed weights are
 * shared by any number of sessions, on any threads. A session owns the activation
 * arena planned for one input size and runs one frame at a time; use one session per
 * stream (camera) and thread. Every function returns a status; on failure
 * roadnn_last_error() gives a one-line message for the calling thread. Nothing here
 * throws, aborts on bad input, reads the environment or prints.
 *
 *   roadnn_model_params mp = roadnn_model_default_params(ROADNN_MODEL_STIXELNEXT);
 *   roadnn_model* model;
 *   if (roadnn_model_load_file("stixelnext.safetensors", &mp, &model) != ROADNN_OK)
 *     fprintf(stderr, "%s\n", roadnn_last_error());
 *   roadnn_session_params sp = roadnn_session_default_params();
 *   roadnn_session* session;
 *   roadnn_session_create(model, &sp, &session);
 *   roadnn_image image = {pixels, width, height, 0};
 *   roadnn_stixel_world world;
 *   roadnn_stixel_run(session, &image, &camera, NULL, &world);
 *   ... world.stixels[i].depth, world.stixels[i].top_point ...
 *   roadnn_session_free(session);
 *   roadnn_model_free(model);
 */
#ifndef ROADNN_H
#define ROADNN_H

#include <stddef.h>
#include <stdint.h>

#if defined(ROADNN_BUILDING) && defined(__GNUC__)
#define ROADNN_API __attribute__((visibility("default")))
#else
#define ROADNN_API
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* ---- status and errors ------------------------------------------------------- */

typedef enum roadnn_status {
  ROADNN_OK = 0,
  ROADNN_ERROR_INVALID_ARGUMENT = 1, /* null pointer, wrong buffer size, option out of range */
  ROADNN_ERROR_WRONG_MODEL = 2,      /* a call for another kind of model than the session's */
  ROADNN_ERROR_IO = 3,               /* a file cannot be opened or read */
  ROADNN_ERROR_BAD_MODEL = 4,        /* weights malformed, or not the model asked for */
  ROADNN_ERROR_UNSUPPORTED = 5,      /* an option this CPU or build cannot run (e.g. bf16) */
  ROADNN_ERROR_OUT_OF_MEMORY = 6,
  ROADNN_ERROR_INTERNAL = 7
} roadnn_status;

/* "0.2.0". */
ROADNN_API const char* roadnn_version(void);
/* "ok", "invalid argument", ... */
ROADNN_API const char* roadnn_status_name(roadnn_status status);
/* The calling thread's message for its most recent call into roadnn: one line saying
 * what failed, or "" when that call succeeded. Valid until the thread's next call. */
ROADNN_API const char* roadnn_last_error(void);

/* ---- models ------------------------------------------------------------------- */

typedef enum roadnn_model_kind {
  ROADNN_MODEL_CONVNEXT = 1,   /* torchvision ConvNeXt `features` (any T/S/B config) */
  ROADNN_MODEL_STIXELNEXT = 2, /* StixelNExT++: ConvNeXt-Tiny + stixel head */
  ROADNN_MODEL_FASTERRCNN_MOBILENET_V3_LARGE_FPN = 3,
  ROADNN_MODEL_FASTERRCNN_MOBILENET_V3_LARGE_320_FPN = 4,
  ROADNN_MODEL_FASTERRCNN_RESNET50_FPN = 5
} roadnn_model_kind;

/* Highest kernel set a model may use; the CPU's own limit always applies too. */
typedef enum roadnn_isa {
  ROADNN_ISA_SCALAR = 0,
  ROADNN_ISA_AVX2 = 1,   /* AVX2 + FMA */
  ROADNN_ISA_AVX512 = 2, /* AVX-512 F/BW/DQ/VL */
  ROADNN_ISA_NEON = 3,   /* aarch64 Advanced SIMD; a cap of avx2/avx512 on ARM means neon */
  ROADNN_ISA_BEST = 99   /* whatever the CPU has (default) */
} roadnn_isa;

typedef enum roadnn_precision {
  ROADNN_PRECISION_F32 = 0, /* default: matches PyTorch's float32 */
  ROADNN_PRECISION_BF16 = 1 /* ConvNeXt MLP products in bfloat16; needs AVX512_BF16 */
} roadnn_precision;

typedef struct roadnn_model_params {
  roadnn_model_kind kind;
  roadnn_isa max_isa;         /* default ROADNN_ISA_BEST */
  int winograd;               /* detectors' 3x3 stride-1 convolutions as Winograd F(4x4,3x3):
                                 1 (default) or 0 (direct form: exact to ~1e-6 instead of ~1e-5) */
  roadnn_precision precision; /* ConvNeXt and StixelNExT++ only; default F32 */

  /* StixelNExT++: 0 / NULL take the weights' __metadata__ (stixelnext.* keys), else
   * the published defaults (1280x1920 input, 8-px columns, tangent anchors, raw 0..255). */
  int stixel_head;            /* -1 (default): detect from the tensors; 0..4: V0..V4 */
  int input_height, input_width;
  int columns, stixel_width;
  const char* anchors;        /* "tangent:4,66,64" or "linear:START,END,N" */
  const char* normalization;  /* "raw255", "unit" or "imagenet" */

  /* Faster R-CNN: the number of classes (background included) comes from the weights. */
  float box_score_thresh;     /* < 0 (default): torchvision's 0.05 */
} roadnn_model_params;

typedef struct roadnn_model roadnn_model;

ROADNN_API roadnn_model_params roadnn_model_default_params(roadnn_model_kind kind);

/* Loads safetensors weights (state_dict names, see weights/export.py): from a file
 * (memory-mapped, read-only) or from the caller's bytes (copied while loading; the
 * buffer may be freed afterwards). Both validate every tensor; the first problem is
 * the error. *out is NULL on failure. */
ROADNN_API roadnn_status roadnn_model_load_file(const char* path, const roadnn_model_params* params,
                                                roadnn_model** out);
ROADNN_API roadnn_status roadnn_model_load_memory(const void* data, size_t size,
                                                  const roadnn_model_params* params, roadnn_model** out);
/* NULL is ignored. Free every session of a model before the model. */
ROADNN_API void roadnn_model_free(roadnn_model* model);

typedef struct roadnn_model_info {
  roadnn_model_kind kind;
  const char* kernels;     /* the kernel set chosen at load: "scalar", "avx2", "avx512" */
  size_t weight_bytes;     /* packed weights, shared by all sessions */
  int num_classes;         /* detectors: classes incl. background; else 0 */
  int input_height, input_width; /* StixelNExT++: the network input size; else 0 */
  int columns;             /* StixelNExT++: stixel columns U; else 0 */
  const char* stixel_head; /* StixelNExT++: "v0".."v4"; else "" */
  int stage_widths[4];     /* ConvNeXt and StixelNExT++: the backbone's channels per stage */
  int stage_depths[4];     /* ... and blocks per stage (ConvNeXt-Tiny: 96,192,384,768 / 3,3,9,3); else 0 */
} roadnn_model_info;
ROADNN_API roadnn_status roadnn_model_get_info(const roadnn_model* model, roadnn_model_info* out);

/* Warnings found while loading (e.g. tensors the model does not use, a V1/V3 head
 * that could be either): one line each, valid as long as the model. */
ROADNN_API size_t roadnn_model_warning_count(const roadnn_model* model);
ROADNN_API const char* roadnn_model_warning(const roadnn_model* model, size_t index);

/* ---- sessions ----------------------------------------------------------------- */

typedef struct roadnn_session_params {
  int threads; /* 0 (default): all cores; the session's own team (the calling thread plus
                  threads - 1 engine workers), unaffected by the caller's OpenMP settings.
                  Results are bitwise the same for any count. */
  int height, width; /* the input size to plan for (0: the model's natural size).
                        ConvNeXt: the tensor's H x W (required).
                        StixelNExT++: ignored (images of any size are resized to the network input).
                        Detectors: the image size (required); another size re-plans on the fly. */
  int batch;         /* ConvNeXt only: N (default 1) */
} roadnn_session_params;

typedef struct roadnn_session roadnn_session;

ROADNN_API roadnn_session_params roadnn_session_default_params(void);
/* The session keeps a reference to the model; the model must outlive it. *out is NULL
 * on failure. */
ROADNN_API roadnn_status roadnn_session_create(const roadnn_model* model, const roadnn_session_params* params,
                                               roadnn_session** out);
ROADNN_API void roadnn_session_free(roadnn_session* session);

/* Intermediate tensors (numerics debugging, docs/NUMERICS.md). When a callback is set,
 * every run of the session calls it once per intermediate tensor that has a PyTorch
 * counterpart, in network order, on the calling thread, before the run returns:
 *   name    the PyTorch module's qualified name ("features.1.0", "classifier.up",
 *           "backbone.body.layer2.0", "rpn.head.cls_logits#2", "rpn.head[0][2]", ...)
 *   shape   rank dimensions, exactly as the PyTorch module returns the tensor (NCHW for
 *           convolutions and blocks)
 *   data    the float32 elements in that layout, valid only during the call
 *   covers  "" or, where the engine fuses layers, the comma-separated PyTorch modules
 *           this tensor stands for
 * Off by default (callback NULL); off costs nothing and a run allocates nothing. A set
 * callback makes runs slower (layout conversion, and allocation on the first one). */
typedef void (*roadnn_dump_fn)(const char* name, const int64_t* shape, int rank, const float* data,
                               const char* covers, void* user_data);
/* callback NULL switches the dump off. */
ROADNN_API roadnn_status roadnn_session_set_dump(roadnn_session* session, roadnn_dump_fn callback, void* user_data);

/* Interleaved 8-bit RGB in the caller's memory. stride: bytes per row, 0 = 3 * width. */
typedef struct roadnn_image {
  const uint8_t* data;
  int width, height;
  size_t stride;
} roadnn_image;

/* ---- ConvNeXt features -------------------------------------------------------- */

/* input: NCHW float [batch, 3, height, width] as PyTorch's (input_count floats).
 * output: NCHW [batch, C, height/32, width/32] (output_count floats, see
 * roadnn_convnext_output_shape). */
ROADNN_API roadnn_status roadnn_convnext_output_shape(const roadnn_session* session, int64_t shape[4]);
ROADNN_API roadnn_status roadnn_convnext_run(roadnn_session* session, const float* input, size_t input_count,
                                             float* output, size_t output_count);

/* ---- StixelNExT++ ------------------------------------------------------------- */

/* The camera of the image as given (before any resize; the library scales K). */
typedef struct roadnn_camera {
  double K[9];  /* 3x3 intrinsics, row-major */
  double T[16]; /* 4x4 world -> camera, row-major; ignored unless has_T */
  int has_T;    /* 0: T = identity (points in the optical camera frame: x right, y down, z forward) */
} roadnn_camera;

typedef struct roadnn_stixel_params {
  double threshold;   /* keep candidates with probability >= threshold, in [0, 1] (default 0.36) */
  double train_focal; /* > 0: depths scaled by f_camera / train_focal (needs a camera); default 0 */
  int cluster;        /* 1: DBSCAN on the top points in the (axis_a, axis_b) plane (needs a camera) */
  double cluster_eps; /* metres (default 1.42) */
  int cluster_min_samples; /* default 2 */
  int axis_a, axis_b; /* default 0, 2 (x, z of the optical frame) */
} roadnn_stixel_params;

typedef struct roadnn_stixel {
  int u, top, bottom;  /* column centre, top and bottom row, in network-input pixels */
  int width;           /* pixels */
  float depth;         /* metres */
  float confidence;    /* existence probability */
  int cluster;         /* cluster id, -1 noise; 0 without clustering */
  double top_point[3]; /* 3D point at (u, top, depth); zeros without a camera */
  double bottom_point[3];
} roadnn_stixel;

typedef struct roadnn_stixel_world {
  const roadnn_stixel* stixels; /* owned by the session, valid until its next run */
  size_t count;
  int clusters;                 /* highest cluster label (-1: none) */
  int image_width, image_height; /* the network input the stixel rows refer to */
  double K[9];                  /* the camera scaled to that size (zeros without a camera) */
  int resized;                  /* 1 if the image was resized to the network input */
} roadnn_stixel_world;

ROADNN_API roadnn_stixel_params roadnn_stixel_default_params(void);
/* camera may be NULL (no 3D points, no clustering); params NULL = defaults. */
ROADNN_API roadnn_status roadnn_stixel_run(roadnn_session* session, const roadnn_image* image,
                                           const roadnn_camera* camera, const roadnn_stixel_params* params,
                                           roadnn_stixel_world* out);

/* ---- Faster R-CNN ------------------------------------------------------------- */

typedef struct roadnn_detection {
  float x1, y1, x2, y2; /* original-image pixels */
  float score;
  int label;            /* torchvision's label: 1.. (0 is background) */
} roadnn_detection;

typedef struct roadnn_detections {
  const roadnn_detection* items; /* owned by the session, valid until its next run */
  size_t count;
} roadnn_detections;

/* The image as torchvision's eval input (RGB / 255). */
ROADNN_API roadnn_status roadnn_detect(roadnn_session* session, const roadnn_image* image,
                                       roadnn_detections* out);

/* ---- SHLE: streaming clearance-height estimation ------------------------------ */

typedef struct roadnn_box {
  double x0, y0, x1, y1; /* pixels, top-left and bottom-right corners */
  double score;
} roadnn_box;

typedef struct roadnn_shle_params {
  /* stereo calibration */
  int width, height;      /* frame size in pixels: every pushed frame has it (required) */
  double fx, fy, cx, cy;  /* left camera, pixels */
  double bf;              /* baseline x focal length, metre-pixels */
  double mount_height;    /* camera height above the road, metres (default 1.45) */
  /* stage 2 (defaults: the released code's) */
  double extend_top, extend_bottom; /* pixels added to the box (20, 20) */
  double min_height;      /* points below this height are dropped (1.5 m) */
  double bandwidth;       /* KDE bandwidth, metres (2.5) */
  double sigma;           /* half width of the depth window, metres (0.6) */
  int lowest_n;           /* lowest points averaged (10) */
  /* boxes */
  int widest_rule;        /* 0 (default): the paper's filter rule; 1: the released widest box */
  double min_score;       /* candidates need score > min_score (0.3) */
  const char* tracker;    /* "ncc" (default), "mil" or "none": fills frames without a box */
  int max_track_frames;   /* frames tracked after the last box (default 30, 0: no limit) */
  /* temporal */
  int use_kalman;         /* 1 (default); the released code's off-by-one mode cannot stream */
  double kalman_q, kalman_r, kalman_p0; /* 1e-3, 1e-2, 6.0 */
} roadnn_shle_params;

typedef struct roadnn_shle roadnn_shle;

typedef struct roadnn_shle_frame {
  int index;           /* 0-based frame number since create/reset */
  int has_box;         /* a box was chosen or tracked */
  int tracked;         /* ... by the tracker */
  roadnn_box box;
  int has_height;      /* stage 2 found a height in this frame */
  double height;       /* metres */
  int has_filtered;
  double filtered;     /* Kalman-filtered height of this frame */
  int has_scene_height;
  double scene_height; /* mean of the filtered heights so far */
  const char* problem; /* why there is no height ("" otherwise); valid until the next push */
} roadnn_shle_frame;

ROADNN_API roadnn_shle_params roadnn_shle_default_params(void);
/* detector: optional Faster R-CNN model (NULL: the caller passes boxes); it must outlive
 * the estimator. threads: the detector session's threads (0: all cores). */
ROADNN_API roadnn_status roadnn_shle_create(const roadnn_shle_params* params, const roadnn_model* detector,
                                            int threads, roadnn_shle** out);
ROADNN_API void roadnn_shle_free(roadnn_shle* shle);
ROADNN_API roadnn_status roadnn_shle_reset(roadnn_shle* shle);
/* One frame: disparity (float pixels, row-major, width x height; <= 0 or NaN = invalid),
 * candidate boxes (boxes/box_count; NULL/0 with a detector, which then finds them in
 * `left`), and the left image (needed by the detector and the tracker; may be NULL
 * otherwise). */
ROADNN_API roadnn_status roadnn_shle_push(roadnn_shle* shle, const float* disparity, int width, int height,
                                          const roadnn_box* boxes, size_t box_count, const roadnn_image* left,
                                          roadnn_shle_frame* out);

#ifdef __cplusplus
}
#endif

#endif /* ROADNN_H */
