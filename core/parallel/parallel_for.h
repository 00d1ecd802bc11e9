#pragma once
// The one parallel loop of the core: `threads` workers, cancellation checked before each
// iteration, and an exception inside an iteration carried out of the loop (an exception that
// leaves an OpenMP region aborts the process) and rethrown after it.
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>

#include "core/parallel/cancel.h"

namespace bathyslam {

// Calls body(i) for i in [0, n) on `threads` threads (at least 1), dynamically scheduled in
// chunks of `chunk`. After the loop: the first exception an iteration threw is rethrown, else
// Cancelled if `cancel` was set.
template <typename Body>
void parallel_for(std::size_t n, int threads, const std::atomic<bool>* cancel, Body&& body, int chunk = 1) {
  std::exception_ptr failure;
  std::once_flag first;
  std::atomic<bool> failed = false;
  auto iteration = [&](std::size_t i) {
    if (failed.load() || (cancel != nullptr && cancel->load())) return;
    try {
      body(i);
    } catch (...) {
      std::call_once(first, [&] { failure = std::current_exception(); });
      failed = true;
    }
  };
  if (threads <= 1) {
    // No OpenMP region for one thread: FLANN opens one of its own for every query PCL's
    // KD-trees make, and nested inside ours each of those builds and frees a team (a third of
    // a registration's CPU on `lake`, most of it futex calls); at the top level libgomp reuses
    // one team instead. Same iterations in the same order as the one-thread region.
    for (std::size_t i = 0; i < n; ++i) iteration(i);
  } else {
#pragma omp parallel for schedule(dynamic, chunk) num_threads(threads)
    for (std::size_t i = 0; i < n; ++i) iteration(i);
  }
  if (failure) std::rethrow_exception(failure);
  throw_if_cancelled(cancel);
}

}  // namespace bathyslam
