// roadnn C++ API: RAII handles over the C API of roadnn.h (the same implementation;
// no engine type appears here). Failures throw roadnn::Error with the status and the
// library's message. Header-only, C++17.
//
//   roadnn::Model model("stixelnext.safetensors", roadnn::Model::defaults(ROADNN_MODEL_STIXELNEXT));
//   roadnn::Session left(model), right(model);   // share the weights; one per thread
//   roadnn_stixel_world world = left.stixels(image, &camera);
#ifndef ROADNN_HPP
#define ROADNN_HPP

#include <cstddef>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "roadnn/roadnn.h"

namespace roadnn {

class Error : public std::runtime_error {
 public:
  Error(roadnn_status status, const std::string& message) : std::runtime_error(message), status_(status) {}
  roadnn_status status() const { return status_; }

 private:
  roadnn_status status_;
};

inline void check(roadnn_status status) {
  if (status != ROADNN_OK) throw Error(status, roadnn_last_error());
}

// A loaded model: immutable, shareable by any number of sessions on any threads.
class Model {
 public:
  static roadnn_model_params defaults(roadnn_model_kind kind) { return roadnn_model_default_params(kind); }
  Model(const std::string& path, const roadnn_model_params& params) {
    check(roadnn_model_load_file(path.c_str(), &params, &m_));
  }
  Model(const void* data, std::size_t size, const roadnn_model_params& params) {
    check(roadnn_model_load_memory(data, size, &params, &m_));
  }
  ~Model() { roadnn_model_free(m_); }
  Model(const Model&) = delete;
  Model& operator=(const Model&) = delete;
  Model(Model&& o) noexcept : m_(std::exchange(o.m_, nullptr)) {}
  Model& operator=(Model&& o) noexcept {
    std::swap(m_, o.m_);
    return *this;
  }

  roadnn_model_info info() const {
    roadnn_model_info i;
    check(roadnn_model_get_info(m_, &i));
    return i;
  }
  std::vector<std::string> warnings() const {
    std::vector<std::string> w;
    for (std::size_t i = 0; i < roadnn_model_warning_count(m_); ++i) w.emplace_back(roadnn_model_warning(m_, i));
    return w;
  }
  const roadnn_model* get() const { return m_; }

 private:
  roadnn_model* m_ = nullptr;
};

// One stream's state (activation arena); one frame at a time. Must not outlive its model.
class Session {
 public:
  static roadnn_session_params defaults() { return roadnn_session_default_params(); }
  explicit Session(const Model& model, const roadnn_session_params& params = defaults()) {
    check(roadnn_session_create(model.get(), &params, &s_));
  }
  ~Session() { roadnn_session_free(s_); }
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;
  Session(Session&& o) noexcept : s_(std::exchange(o.s_, nullptr)) {}
  Session& operator=(Session&& o) noexcept {
    std::swap(s_, o.s_);
    return *this;
  }

  // Intermediate tensors of every run to `callback` (null: off), see roadnn_session_set_dump.
  void set_dump(roadnn_dump_fn callback, void* user_data) { check(roadnn_session_set_dump(s_, callback, user_data)); }

  // ConvNeXt: NCHW in, NCHW out ([N, C, H/32, W/32]).
  std::vector<std::int64_t> convnext_output_shape() const {
    std::int64_t s[4];
    check(roadnn_convnext_output_shape(s_, s));
    return {s[0], s[1], s[2], s[3]};
  }
  std::vector<float> convnext(const std::vector<float>& input) {
    std::size_t count = 1;
    for (std::int64_t d : convnext_output_shape()) count *= static_cast<std::size_t>(d);
    std::vector<float> out(count);
    check(roadnn_convnext_run(s_, input.data(), input.size(), out.data(), out.size()));
    return out;
  }
  // StixelNExT++: the world's arrays stay valid until this session's next run.
  roadnn_stixel_world stixels(const roadnn_image& image, const roadnn_camera* camera = nullptr,
                              const roadnn_stixel_params* params = nullptr) {
    roadnn_stixel_world w;
    check(roadnn_stixel_run(s_, &image, camera, params, &w));
    return w;
  }
  // Faster R-CNN: copies of the detections.
  std::vector<roadnn_detection> detect(const roadnn_image& image) {
    roadnn_detections d;
    check(roadnn_detect(s_, &image, &d));
    return std::vector<roadnn_detection>(d.items, d.items + d.count);
  }
  roadnn_session* get() { return s_; }

 private:
  roadnn_session* s_ = nullptr;
};

// SHLE: streaming clearance-height estimation, one frame per push().
class HeightEstimator {
 public:
  static roadnn_shle_params defaults() { return roadnn_shle_default_params(); }
  explicit HeightEstimator(const roadnn_shle_params& params, const Model* detector = nullptr, int threads = 0) {
    check(roadnn_shle_create(&params, detector ? detector->get() : nullptr, threads, &h_));
  }
  ~HeightEstimator() { roadnn_shle_free(h_); }
  HeightEstimator(const HeightEstimator&) = delete;
  HeightEstimator& operator=(const HeightEstimator&) = delete;

  roadnn_shle_frame push(const float* disparity, int width, int height, const std::vector<roadnn_box>& boxes,
                         const roadnn_image* left = nullptr) {
    roadnn_shle_frame f;
    check(roadnn_shle_push(h_, disparity, width, height, boxes.empty() ? nullptr : boxes.data(), boxes.size(), left,
                           &f));
    return f;
  }
  void reset() { check(roadnn_shle_reset(h_)); }

 private:
  roadnn_shle* h_ = nullptr;
};

inline std::string version() { return roadnn_version(); }

}  // namespace roadnn

#endif  // ROADNN_HPP
