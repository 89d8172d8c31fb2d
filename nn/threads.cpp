#include "nn/threads.h"

#include "nn/exec.h"

#ifdef ROADNN_OPENMP
#include <omp.h>
#endif

namespace nn {

ExecOptions& mutable_exec();  // nn/exec.cpp

void set_num_threads(int n) { mutable_exec().threads = n; }

int num_threads() {
#ifdef ROADNN_OPENMP
  const int n = current_exec().threads;
  return n > 0 ? n : omp_get_num_procs();
#else
  return 1;
#endif
}

int thread_index() {
#ifdef ROADNN_OPENMP
  return omp_get_thread_num();
#else
  return 0;
#endif
}

int team_size() {
#ifdef ROADNN_OPENMP
  return omp_in_parallel() ? 1 : num_threads();
#else
  return 1;
#endif
}

}  // namespace nn
