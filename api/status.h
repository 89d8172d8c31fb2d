// Error handling of the C API: every entry point runs its body through guarded(),
// which turns any exception into a status and the calling thread's last-error message,
// so that nothing escapes into C code.
#pragma once

#include <string>

#include "roadnn/roadnn.h"

namespace roadnn_api {

// An error the API raises itself, with the status it maps to.
struct ApiError {
  roadnn_status status;
  std::string message;
};

[[noreturn]] void fail(roadnn_status status, const std::string& message);
// fail(ROADNN_ERROR_INVALID_ARGUMENT, "<function>: <what> is null") when p is null.
void require(const void* p, const char* function, const char* what);

void set_last_error(const std::string& message);
void clear_last_error();

// Runs f; returns ROADNN_OK, or the status of the ApiError / exception thrown (library
// errors map to `library_status`: ROADNN_ERROR_BAD_MODEL while loading, else
// ROADNN_ERROR_INVALID_ARGUMENT), with its message stored for roadnn_last_error().
template <class F>
roadnn_status guarded(roadnn_status library_status, F&& f);

roadnn_status status_of_current_exception(roadnn_status library_status);

template <class F>
roadnn_status guarded(roadnn_status library_status, F&& f) {
  try {
    clear_last_error();
    f();
    return ROADNN_OK;
  } catch (...) {
    return status_of_current_exception(library_status);
  }
}

}  // namespace roadnn_api
