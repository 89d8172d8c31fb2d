/* The public C header compiles as C99 (-std=c99 -pedantic -Wall -Wextra -Werror) and
 * links against the library: prints the version, some defaults and the status of a
 * failing call, which ctest matches. */
#include <stdio.h>
#include <string.h>

#include "roadnn/roadnn.h"

int main(void) {
  roadnn_model_params mp = roadnn_model_default_params(ROADNN_MODEL_STIXELNEXT);
  roadnn_session_params sp = roadnn_session_default_params();
  roadnn_stixel_params tp = roadnn_stixel_default_params();
  roadnn_model* model = (roadnn_model*)&mp; /* must come back NULL */
  roadnn_status status = roadnn_model_load_file(NULL, &mp, &model);
  const char* message = roadnn_last_error();
  int ok = status == ROADNN_ERROR_INVALID_ARGUMENT && model == NULL && message != NULL && strlen(message) > 0;
  printf("roadnn %s\n", roadnn_version());
  printf("model: kind %d max_isa %d winograd %d precision %d stixel_head %d\n", (int)mp.kind, (int)mp.max_isa,
         mp.winograd, (int)mp.precision, mp.stixel_head);
  printf("session: threads %d batch %d\n", sp.threads, sp.batch);
  printf("stixel: threshold %.2f cluster %d min_samples %d axes %d %d\n", tp.threshold, tp.cluster,
         tp.cluster_min_samples, tp.axis_a, tp.axis_b);
  printf("load(NULL): %s: %s\n", roadnn_status_name(status), message);
  roadnn_model_free(NULL);
  roadnn_session_free(NULL);
  printf(ok ? "c99 ok\n" : "c99 FAILED\n");
  return ok ? 0 : 1;
}
