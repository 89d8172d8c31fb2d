// roadnn_session_*: a copy of the model's engine object (sharing its weights) with
// its own arena, planned under the session's ExecOptions.
#include <limits>

#include "api/handles.h"
#include "api/status.h"

namespace roadnn_api {

void require_kind(const roadnn_session* s, bool ok, const char* function, const char* wanted) {
  if (!ok)
    fail(ROADNN_ERROR_WRONG_MODEL, std::string(function) + ": the session runs a " + kind_name(s->model->kind) +
                                       " model, not " + wanted);
}

void check_image(const roadnn_image* image, const char* function) {
  require(image, function, "image");
  require(image->data, function, "image->data");
  if (image->width < 1 || image->height < 1 || image->width > 65535 || image->height > 65535)
    fail(ROADNN_ERROR_INVALID_ARGUMENT, std::string(function) + ": image size " + std::to_string(image->width) + "x" +
                                            std::to_string(image->height) + " is not in [1, 65535]");
  const std::size_t row = static_cast<std::size_t>(image->width) * 3;
  if (image->stride != 0 && image->stride < row)
    fail(ROADNN_ERROR_INVALID_ARGUMENT, std::string(function) + ": image stride " + std::to_string(image->stride) +
                                            " is below 3 x width = " + std::to_string(row));
}

}  // namespace roadnn_api

using namespace roadnn_api;

extern "C" {

roadnn_session_params roadnn_session_default_params(void) {
  roadnn_session_params p;
  p.threads = 0;
  p.height = p.width = 0;
  p.batch = 1;
  return p;
}

roadnn_status roadnn_session_create(const roadnn_model* model, const roadnn_session_params* params,
                                    roadnn_session** out) {
  if (out) *out = nullptr;
  return guarded(ROADNN_ERROR_INVALID_ARGUMENT, [&] {
    const char* fn = "roadnn_session_create";
    require(out, fn, "out");
    require(model, fn, "model");
    require(params, fn, "params");
    if (params->threads < 0 || params->threads > 1024)
      fail(ROADNN_ERROR_INVALID_ARGUMENT, "roadnn_session_params.threads must be in [0, 1024]");
    auto s = std::make_unique<roadnn_session>();
    s->model = model;
    s->exec = model->exec;
    s->exec.threads = params->threads;
    nn::ExecScope scope(s->exec);
    if (model->convnext) {
      if (params->batch < 1 || params->batch > 4096)
        fail(ROADNN_ERROR_INVALID_ARGUMENT, "roadnn_session_params.batch must be in [1, 4096]");
      if (params->height < 32 || params->width < 32 || params->height > 16384 || params->width > 16384)
        fail(ROADNN_ERROR_INVALID_ARGUMENT,
             "a ConvNeXt session needs roadnn_session_params.height and .width in [32, 16384]");
      s->batch = params->batch;
      s->height = params->height;
      s->width = params->width;
      s->convnext = std::make_unique<nn::ConvNeXt>(*model->convnext);
      s->convnext->plan(s->batch, s->height, s->width);
    } else if (model->stixelnext) {
      s->predictor = std::make_unique<stixel::Predictor>(*model->stixelnext, model->stixel_settings);
    } else if (model->detector) {
      if (params->height != 0 || params->width != 0) {
        if (params->height < 32 || params->width < 32 || params->height > 16384 || params->width > 16384)
          fail(ROADNN_ERROR_INVALID_ARGUMENT,
               "a detector session's roadnn_session_params.height and .width must be 0 or in [32, 16384]");
      }
      s->detector = std::make_unique<nn::detection::FasterRcnn>(*model->detector);
      if (params->height != 0) {
        s->height = params->height;
        s->width = params->width;
        s->detector->plan(s->height, s->width);
      }
    } else {
      fail(ROADNN_ERROR_INTERNAL, "roadnn_session_create: the model holds no network");
    }
    *out = s.release();
  });
}

void roadnn_session_free(roadnn_session* session) { delete session; }

}  // extern "C"
