#include "nn/threads.h"

#ifdef ROADNN_OPENMP
#include <omp.h>
#endif

namespace nn {

void set_num_threads(int n) {
#ifdef ROADNN_OPENMP
  if (n <= 0) n = omp_get_num_procs();
  omp_set_num_threads(n);
#else
  (void)n;
#endif
}

int num_threads() {
#ifdef ROADNN_OPENMP
  return omp_get_max_threads();
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

}  // namespace nn
