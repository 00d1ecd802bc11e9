#include "server/scheduler/retry.h"

#include <algorithm>
#include <thread>

namespace bathyslam::server {

bool sleep_unless(const std::atomic<bool>& stop, std::chrono::milliseconds duration) {
  constexpr auto kSlice = std::chrono::milliseconds(100);  // how soon a stop is noticed
  const auto end = std::chrono::steady_clock::now() + duration;
  while (!stop) {
    const auto now = std::chrono::steady_clock::now();
    if (now >= end) return true;
    std::this_thread::sleep_for(std::min<std::chrono::steady_clock::duration>(kSlice, end - now));
  }
  return false;
}

}  // namespace bathyslam::server
