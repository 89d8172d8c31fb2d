// The execution options of a model or session: the highest ISA its kernels may use,
// its thread count and whether 3x3 convolutions are packed for Winograd. There is no
// process-wide setting: the options live in an ExecScope, which a model's loader and a
// session's run open on the calling thread for the duration of that call (and
// restore on exit), so two models in one process, or two sessions on two threads,
// never see each other's options. Code outside parallel regions reads them through
// active_isa(), num_threads() and winograd_enabled(); every parallel region of the
// engine (nn/threads.h) sizes its team by num_threads() alone.
#pragma once

#include "nn/isa.h"

namespace nn {

struct ExecOptions {
  Isa max_isa = Isa::Avx512;  // a cap (nn/isa.h: cap_isa): the default is the best there is
  int threads = 0;            // <= 0: all cores
  bool winograd = true;       // pack 3x3 stride-1 convolutions for Winograd F(4x4, 3x3)
};

// The calling thread's current options (defaults outside any scope).
const ExecOptions& current_exec();

// The calling thread's current options with `threads` threads instead (for an ExecScope
// that changes only the thread count).
inline ExecOptions with_threads(int threads) {
  ExecOptions o = current_exec();
  o.threads = threads;
  return o;
}

class ExecScope {
 public:
  explicit ExecScope(const ExecOptions& options);
  ~ExecScope();
  ExecScope(const ExecScope&) = delete;
  ExecScope& operator=(const ExecScope&) = delete;

 private:
  ExecOptions saved_;
};

}  // namespace nn
