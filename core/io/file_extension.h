#pragma once
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <string>
#include <string_view>

namespace bathyslam {

// The extension of `path` in lower case (".gsf"): how sonar files are told apart.
inline std::string lowercase_extension(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

// Whether `path` ends in `extension`, given in lower case, in any case.
inline bool has_extension(const std::filesystem::path& path, std::string_view extension) {
  return lowercase_extension(path) == extension;
}

}  // namespace bathyslam
