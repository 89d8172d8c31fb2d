// roadnn_convnext_*: NCHW float in, NCHW features out, as PyTorch's model.features.
#include "api/handles.h"
#include "api/status.h"
#include "nn/layout.h"

using namespace roadnn_api;

extern "C" {

roadnn_status roadnn_convnext_output_shape(const roadnn_session* session, int64_t shape[4]) {
  return guarded(ROADNN_ERROR_INVALID_ARGUMENT, [&] {
    const char* fn = "roadnn_convnext_output_shape";
    require(session, fn, "session");
    require(shape, fn, "shape");
    require_kind(session, session->convnext != nullptr, fn, "a ConvNeXt");
    const nn::Shape o = session->convnext->output_shape();
    shape[0] = o.n, shape[1] = o.c, shape[2] = o.h, shape[3] = o.w;
  });
}

roadnn_status roadnn_convnext_run(roadnn_session* session, const float* input, size_t input_count, float* output,
                                  size_t output_count) {
  return guarded(ROADNN_ERROR_INVALID_ARGUMENT, [&] {
    const char* fn = "roadnn_convnext_run";
    require(session, fn, "session");
    require_kind(session, session->convnext != nullptr, fn, "a ConvNeXt");
    require(input, fn, "input");
    require(output, fn, "output");
    nn::ConvNeXt& m = *session->convnext;
    const std::size_t want_in = m.input_shape().count();
    if (input_count != want_in)
      fail(ROADNN_ERROR_INVALID_ARGUMENT, std::string(fn) + ": input_count is " + std::to_string(input_count) +
                                              " but the session is planned for [" + std::to_string(session->batch) +
                                              ", 3, " + std::to_string(session->height) + ", " +
                                              std::to_string(session->width) + "] = " + std::to_string(want_in));
    const nn::Shape o = m.output_shape();
    if (output_count != o.count())
      fail(ROADNN_ERROR_INVALID_ARGUMENT, std::string(fn) + ": output_count is " + std::to_string(output_count) +
                                              " but the output holds " + std::to_string(o.count()) + " floats");
    nn::ExecScope scope(session->exec);
    const nn::ConstTensorView y = m.forward(input);
    nn::nhwc_to_nchw(y.data, o.n, o.c, o.h, o.w, output);
  });
}

}  // extern "C"
