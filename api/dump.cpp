// roadnn_session_set_dump: the engine's dump receiver (nn/dump.h) behind a C callback.
#include "api/handles.h"
#include "api/status.h"

using namespace roadnn_api;

extern "C" {

roadnn_status roadnn_session_set_dump(roadnn_session* session, roadnn_dump_fn callback, void* user_data) {
  return guarded(ROADNN_ERROR_INVALID_ARGUMENT, [&] {
    require(session, "roadnn_session_set_dump", "session");
    session->dump = callback ? std::make_unique<CallbackDump>(callback, user_data) : nullptr;
    nn::DumpSink* sink = session->dump.get();
    if (session->convnext) session->convnext->set_dump(sink);
    if (session->predictor) session->predictor->model().set_dump(sink);
    if (session->detector) session->detector->set_dump(sink);
  });
}

}  // extern "C"
