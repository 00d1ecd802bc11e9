#pragma once
// The pipeline's one parallel loop: `threads` workers, cancellation checked before each
// iteration, and an exception inside an iteration carried out of the loop (an exception that
// leaves an OpenMP region aborts the process) and rethrown after it.
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>

#include "core/pipeline/cancel.h"

namespace bathyslam {

// Calls body(i) for i in [0, n) on `threads` threads (at least 1), dynamically scheduled in
// chunks of `chunk`. After the loop: the first exception an iteration threw is rethrown, else
// Cancelled if `cancel` was set.
template <typename Body>
void parallel_for(std::size_t n, int threads, const std::atomic<bool>* cancel, Body&& body, int chunk = 1) {
  std::exception_ptr failure;
  std::once_flag first;
  std::atomic<bool> failed = false;
#pragma omp parallel for schedule(dynamic, chunk) num_threads(threads < 1 ? 1 : threads)
  for (std::size_t i = 0; i < n; ++i) {
    if (failed.load() || (cancel != nullptr && cancel->load())) continue;
    try {
      body(i);
    } catch (...) {
      std::call_once(first, [&] { failure = std::current_exception(); });
      failed = true;
    }
  }
  if (failure) std::rethrow_exception(failure);
  throw_if_cancelled(cancel);
}

}  // namespace bathyslam
