// What the C API's opaque handles hold. A model keeps the loaded, never planned
// engine objects (const: their packed weights are shared by every session, see
// nn/buffer.h); a session copies the model's object, which shares those weights, and
// plans its own arena under its own ExecOptions.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "nn/dump.h"
#include "nn/exec.h"
#include "nn/models/convnext.h"
#include "nn/models/detection/faster_rcnn.h"
#include "nn/models/stixelnext.h"
#include "roadnn/roadnn.h"
#include "stixel/predictor.h"

struct roadnn_model {
  roadnn_model_kind kind = ROADNN_MODEL_CONVNEXT;
  nn::ExecOptions exec;  // max_isa and winograd as loaded (threads: per session)
  std::vector<std::string> warnings;
  std::shared_ptr<const nn::ConvNeXt> convnext;
  std::shared_ptr<const nn::StixelNExT> stixelnext;
  stixel::ModelSettings stixel_settings;
  std::shared_ptr<const nn::detection::FasterRcnn> detector;
  std::size_t weight_bytes = 0;
};

namespace roadnn_api {

// roadnn_session_set_dump's callback as the engine's dump receiver.
class CallbackDump : public nn::DumpSink {
 public:
  CallbackDump(roadnn_dump_fn fn, void* user) : fn_(fn), user_(user) {}
  bool wants(const std::string&) const override { return true; }
  void tensor(const std::string& name, const std::vector<std::int64_t>& shape, const float* data,
              const std::string& covers) override {
    fn_(name.c_str(), shape.data(), static_cast<int>(shape.size()), data, covers.c_str(), user_);
  }

 private:
  roadnn_dump_fn fn_;
  void* user_;
};

}  // namespace roadnn_api

struct roadnn_session {
  const roadnn_model* model = nullptr;
  nn::ExecOptions exec;  // the model's ISA cap and Winograd choice, the session's threads
  int batch = 1, height = 0, width = 0;
  std::unique_ptr<nn::ConvNeXt> convnext;
  std::unique_ptr<stixel::Predictor> predictor;
  std::unique_ptr<nn::detection::FasterRcnn> detector;
  // Staging and results, reused from frame to frame.
  std::vector<float> planar;             // detector input [3, h, w]
  std::vector<roadnn_stixel> stixels;
  std::vector<roadnn_detection> detections;
  std::unique_ptr<roadnn_api::CallbackDump> dump;  // null: off
};

namespace roadnn_api {

bool is_detector(roadnn_model_kind kind);
bool is_known_kind(roadnn_model_kind kind);
const char* kind_name(roadnn_model_kind kind);

// The session's model must be `kind` (else ROADNN_ERROR_WRONG_MODEL naming `function`).
void require_kind(const roadnn_session* s, bool ok, const char* function, const char* wanted);

// Checks an image argument (pointer, size in [1, 65535], stride >= 3 * width or 0).
void check_image(const roadnn_image* image, const char* function);

}  // namespace roadnn_api
