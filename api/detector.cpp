// roadnn_detect: an RGB buffer -> torchvision Faster R-CNN detections.
#include "api/handles.h"
#include "api/status.h"

using namespace roadnn_api;

extern "C" {

roadnn_status roadnn_detect(roadnn_session* session, const roadnn_image* image, roadnn_detections* out) {
  return guarded(ROADNN_ERROR_INVALID_ARGUMENT, [&] {
    const char* fn = "roadnn_detect";
    require(session, fn, "session");
    require(out, fn, "out");
    require_kind(session, session->detector != nullptr, fn, "a Faster R-CNN");
    check_image(image, fn);
    const int h = image->height, w = image->width;
    if (h < 32 || w < 32)
      fail(ROADNN_ERROR_INVALID_ARGUMENT, std::string(fn) + ": the detectors need images of at least 32x32");
    nn::ExecScope scope(session->exec);
    if (h != session->height || w != session->width) {  // another size: plan again (allocates)
      session->detector->plan(h, w);
      session->height = h;
      session->width = w;
    }
    // torchvision's input: planar RGB in [0, 1], as ToTensor() makes it.
    const std::size_t plane = static_cast<std::size_t>(h) * w;
    const std::size_t stride = image->stride ? image->stride : static_cast<std::size_t>(w) * 3;
    session->planar.resize(3 * plane);
    float* x = session->planar.data();
    for (int y = 0; y < h; ++y) {
      const std::uint8_t* row = image->data + y * stride;
      for (int i = 0; i < w; ++i)
        for (int c = 0; c < 3; ++c) x[c * plane + static_cast<std::size_t>(y) * w + i] = row[3 * i + c] / 255.0f;
    }
    const nn::detection::Detections& d = session->detector->forward(x);
    auto& v = session->detections;
    v.resize(d.boxes.size());
    for (std::size_t i = 0; i < v.size(); ++i) {
      v[i].x1 = d.boxes[i].x1, v[i].y1 = d.boxes[i].y1, v[i].x2 = d.boxes[i].x2, v[i].y2 = d.boxes[i].y2;
      v[i].score = d.scores[i];
      v[i].label = static_cast<int>(d.labels[i]);
    }
    out->items = v.data();
    out->count = v.size();
  });
}

}  // extern "C"
