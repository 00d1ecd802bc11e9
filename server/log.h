#pragma once
// One line per event on stderr, prefixed with UTC time to the millisecond; job lines say "job N".
// Control characters and bytes that are not UTF-8 in the line are escaped (printable(), "\xNN").
#include <cstdarg>

namespace bathyslam::server {

void log(const char* format, ...) __attribute__((format(printf, 1, 2)));

}  // namespace bathyslam::server
