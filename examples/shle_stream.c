/* SHLE streaming: push one stereo frame at a time, read the height so far.
 *
 *   shle_stream [FRAMES]
 *
 * The frames here are synthetic: a level road seen by a camera 1.45 m above it and
 * a height-limit bar 3.3 m above the road at 20 m, in a disparity map the way a
 * stereo matcher would deliver it, with the bar's box as a detector would. */
#include <stdio.h>
#include <stdlib.h>

#include "roadnn/roadnn.h"

int main(int argc, char** argv) {
  const int w = 640, h = 360, frames = argc > 1 ? atoi(argv[1]) : 10;
  const double fx = 500, cx = 320, cy = 180, bf = 0.3 * 500, mount = 1.45, bar = 3.3;
  float* disparity = malloc(sizeof(float) * w * h);
  roadnn_shle_params p = roadnn_shle_default_params();
  roadnn_shle* shle = NULL;
  int i, u, v, status = 0;
  if (!disparity) return 1;
  p.width = w, p.height = h;
  p.fx = p.fy = fx, p.cx = cx, p.cy = cy;
  p.bf = bf, p.mount_height = mount;
  p.tracker = "none"; /* every frame has its box here */
  if (roadnn_shle_create(&p, NULL, 0, &shle) != ROADNN_OK) {
    fprintf(stderr, "%s\n", roadnn_last_error());
    free(disparity);
    return 1;
  }
  for (i = 0; i < frames && status == 0; ++i) {
    /* The bar approaches: 20 m at frame 0, 0.5 m closer per frame. */
    const double z = 20.0 - 0.5 * i;
    const double v_bar = cy - (bar - mount) * fx / z; /* image row of the bar's lower edge */
    roadnn_box box;
    roadnn_shle_frame f;
    for (v = 0; v < h; ++v)
      for (u = 0; u < w; ++u) {
        float d = 0; /* no match */
        if (v > cy + 2) d = (float)(bf * (v - cy) / (fx * mount)); /* road: z = fx * mount / (v - cy) */
        if (v >= v_bar - 12 && v <= v_bar && u >= 200 && u < 440) d = (float)(bf / z); /* the bar */
        disparity[v * w + u] = d;
      }
    box.x0 = 200, box.x1 = 440, box.y0 = v_bar - 12, box.y1 = v_bar, box.score = 0.9;
    if (roadnn_shle_push(shle, disparity, w, h, &box, 1, NULL, &f) != ROADNN_OK) {
      fprintf(stderr, "%s\n", roadnn_last_error());
      status = 1;
      break;
    }
    if (f.has_height)
      printf("frame %2d: bar at %5.2f m, height %.3f m, filtered %.3f m, scene %.3f m\n", f.index, z, f.height,
             f.filtered, f.scene_height);
    else
      printf("frame %2d: no height (%s)\n", f.index, f.problem);
  }
  roadnn_shle_free(shle);
  free(disparity);
  return status;
}
