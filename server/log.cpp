#include "server/log.h"

#include <chrono>
#include <cstdio>
#include <mutex>
#include <string>

#include "core/io/problem.h"
#include "core/types/format.h"

namespace bathyslam::server {

void log(const char* format, ...) {
  const auto now = std::chrono::system_clock::now();
  const auto millis = std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count();
  const std::string stamp = format_utc(static_cast<double>(millis / 1000), "%Y-%m-%dT%H:%M:%S");
  char message[2048];
  va_list args;
  va_start(args, format);
  std::vsnprintf(message, sizeof message, format, args);
  va_end(args);
  // A line is one event: a newline or a terminal escape inside what a line quotes (a survey's
  // name, a job's error) is written as \xNN, so that input cannot forge a line of its own.
  const std::string line = printable(message);
  static std::mutex mutex;  // whole lines, even from several workers
  std::lock_guard lock(mutex);
  std::fprintf(stderr, "%s.%03dZ %s\n", stamp.c_str(), static_cast<int>(millis % 1000), line.c_str());
}

}  // namespace bathyslam::server
