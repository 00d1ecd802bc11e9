#pragma once
// A fresh folder for files that core's writers and readers need on disk (bundle copies, map
// products, plots), removed with everything in it when the ScratchDir goes out of scope.
#include <filesystem>

namespace bathyslam::server {

class ScratchDir {
 public:
  // A new folder "<prefix>.XXXXXX" under `root` (created if needed).
  ScratchDir(const std::filesystem::path& root, const std::string& prefix);
  ~ScratchDir();
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace bathyslam::server
