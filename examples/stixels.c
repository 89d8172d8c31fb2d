/* StixelNExT++ from C: one RGB frame in memory -> stixels with 3D points.
 *
 *   stixels MODEL.safetensors [IMAGE.ppm]
 *
 * The library decodes no image files: this example reads a binary PPM (P6) if one is
 * given, else it draws a synthetic frame, and hands the pixels over as a buffer. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "roadnn/roadnn.h"

static unsigned char* read_ppm(const char* path, int* w, int* h) {
  FILE* f = fopen(path, "rb");
  int maxval = 0;
  unsigned char* px = NULL;
  if (!f) return NULL;
  if (fscanf(f, "P6 %d %d %d", w, h, &maxval) == 3 && maxval == 255 && *w > 0 && *h > 0 && *w <= 16384 &&
      *h <= 16384 && fgetc(f) != EOF) {
    size_t n = (size_t)*w * (size_t)*h * 3;
    px = malloc(n);
    if (px && fread(px, 1, n, f) != n) {
      free(px);
      px = NULL;
    }
  }
  fclose(f);
  return px;
}

static unsigned char* synthetic_frame(int w, int h) {
  unsigned char* px = malloc((size_t)w * (size_t)h * 3);
  int x, y;
  if (!px) return NULL;
  for (y = 0; y < h; ++y)
    for (x = 0; x < w; ++x) {
      unsigned char* p = px + ((size_t)y * w + x) * 3;
      p[0] = (unsigned char)(y < h / 2 ? 120 + x % 64 : 60);  /* "sky" and "road" */
      p[1] = (unsigned char)(y < h / 2 ? 160 : 60 + (x / 16 % 2) * 40);
      p[2] = (unsigned char)(200 - y * 100 / h);
    }
  return px;
}

int main(int argc, char** argv) {
  int w = 640, h = 480;
  unsigned char* pixels;
  size_t i;
  if (argc < 2) {
    fprintf(stderr, "usage: %s MODEL.safetensors [IMAGE.ppm]\n", argv[0]);
    return 2;
  }
  pixels = argc > 2 ? read_ppm(argv[2], &w, &h) : synthetic_frame(w, h);
  if (!pixels) {
    fprintf(stderr, "%s: cannot read a binary PPM (P6, 8 bit) image\n", argc > 2 ? argv[2] : "frame");
    return 1;
  }

  /* The API calls: load, session, run, free. */
  roadnn_model_params mp = roadnn_model_default_params(ROADNN_MODEL_STIXELNEXT);
  roadnn_model* model = NULL;
  roadnn_session* session = NULL;
  if (roadnn_model_load_file(argv[1], &mp, &model) != ROADNN_OK) {
    fprintf(stderr, "%s\n", roadnn_last_error());
    free(pixels);
    return 1;
  }
  roadnn_session_params sp = roadnn_session_default_params();
  roadnn_image image = {pixels, w, h, 0};
  roadnn_camera camera = {{0.9 * w, 0, w / 2.0, 0, 0.9 * w, h / 2.0, 0, 0, 1}, {0}, 0};
  roadnn_stixel_params params = roadnn_stixel_default_params();
  roadnn_stixel_world world;
  params.cluster = 1;
  if (roadnn_session_create(model, &sp, &session) != ROADNN_OK ||
      roadnn_stixel_run(session, &image, &camera, &params, &world) != ROADNN_OK) {
    fprintf(stderr, "%s\n", roadnn_last_error());
    roadnn_session_free(session);
    roadnn_model_free(model);
    free(pixels);
    return 1;
  }

  printf("roadnn %s: %zu stixels on a %dx%d network input, %d clusters\n", roadnn_version(), world.count,
         world.image_width, world.image_height, world.clusters + 1);
  for (i = 0; i < world.count && i < 5; ++i) {
    const roadnn_stixel* s = &world.stixels[i];
    printf("  u %4d rows %4d..%4d depth %6.2f m  P %.2f  top point (%.2f, %.2f, %.2f) m\n", s->u, s->top, s->bottom,
           s->depth, s->confidence, s->top_point[0], s->top_point[1], s->top_point[2]);
  }
  roadnn_session_free(session);
  roadnn_model_free(model);
  free(pixels);
  return 0;
}
