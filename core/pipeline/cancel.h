#pragma once
// Cancellation: a flag the caller sets, checked by the pipeline between units of work.
#include <atomic>
#include <stdexcept>

namespace bathyslam {

class Cancelled : public std::runtime_error {
 public:
  Cancelled() : std::runtime_error("cancelled") {}
};

inline void throw_if_cancelled(const std::atomic<bool>* cancel) {
  if (cancel != nullptr && cancel->load()) throw Cancelled();
}

}  // namespace bathyslam
