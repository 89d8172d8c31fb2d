#include "nn/exec.h"

namespace nn {
namespace {

// The one piece of per-thread state in the engine: the options of the call in
// progress on this thread, set and restored by ExecScope (and by the set_* helpers
// that our tests and apps use between calls).
thread_local ExecOptions t_exec;

}  // namespace

ExecOptions& mutable_exec() { return t_exec; }
const ExecOptions& current_exec() { return t_exec; }

ExecScope::ExecScope(const ExecOptions& options) : saved_(t_exec) { t_exec = options; }
ExecScope::~ExecScope() { t_exec = saved_; }

}  // namespace nn
