#pragma once
// printf-style formatting into a std::string, for the reasons registrations carry in words.
#include <cstdio>
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

}  // namespace bathyslam
