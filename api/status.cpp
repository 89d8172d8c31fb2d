#include "api/status.h"

#include <new>
#include <stdexcept>

#include "api/text.h"

namespace roadnn_api {
namespace {

// The calling thread's message for roadnn_last_error(); per thread so that sessions
// on different threads never see each other's errors.
thread_local std::string t_last_error;

}  // namespace

void fail(roadnn_status status, const std::string& message) { throw ApiError{status, message}; }

void require(const void* p, const char* function, const char* what) {
  if (!p) fail(ROADNN_ERROR_INVALID_ARGUMENT, std::string(function) + ": " + what + " is null");
}

void set_last_error(const std::string& message) { t_last_error = one_line(message); }
void clear_last_error() { t_last_error.clear(); }

roadnn_status status_of_current_exception(roadnn_status library_status) {
  try {
    throw;
  } catch (const ApiError& e) {
    set_last_error(e.message);
    return e.status;
  } catch (const std::bad_alloc&) {
    set_last_error("out of memory");
    return ROADNN_ERROR_OUT_OF_MEMORY;
  } catch (const std::exception& e) {
    set_last_error(e.what());
    return library_status;
  } catch (...) {
    set_last_error("unknown internal error");
    return ROADNN_ERROR_INTERNAL;
  }
}

}  // namespace roadnn_api

extern "C" {

const char* roadnn_last_error(void) { return roadnn_api::t_last_error.c_str(); }

const char* roadnn_status_name(roadnn_status status) {
  switch (status) {
    case ROADNN_OK: return "ok";
    case ROADNN_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case ROADNN_ERROR_WRONG_MODEL: return "wrong model";
    case ROADNN_ERROR_IO: return "i/o error";
    case ROADNN_ERROR_BAD_MODEL: return "bad model";
    case ROADNN_ERROR_UNSUPPORTED: return "unsupported";
    case ROADNN_ERROR_OUT_OF_MEMORY: return "out of memory";
    case ROADNN_ERROR_INTERNAL: return "internal error";
  }
  return "unknown status";
}

}  // extern "C"
