#pragma once
// printf-style formatting into a std::string, for the reasons registrations carry in words, and
// UTC times as text.
#include <cstdio>
#include <ctime>
#include <string>

namespace bathyslam {

template <typename... Args>
std::string format(const char* pattern, Args... args) {
  const int size = std::snprintf(nullptr, 0, pattern, args...);
  if (size <= 0) return {};
  std::string text(static_cast<std::size_t>(size) + 1, '\0');
  std::snprintf(text.data(), text.size(), pattern, args...);
  text.pop_back();
  return text;
}

// `seconds` since the Unix epoch (whole seconds) as UTC text, by a strftime pattern
// ("%Y-%m-%dT%H:%M:%SZ").
inline std::string format_utc(double seconds, const char* pattern) {
  const auto time = static_cast<std::time_t>(seconds);
  std::tm utc{};
  gmtime_r(&time, &utc);
  char text[64];
  return std::string(text, std::strftime(text, sizeof text, pattern, &utc));
}

}  // namespace bathyslam
