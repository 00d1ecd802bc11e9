#pragma once
// A fresh folder for files that core's writers and readers need on disk (bundle copies, map
// products, plots), removed with everything in it when the ScratchDir goes out of scope.
#include <filesystem>
#include <string>

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

// `message` without any "<dir>/" in it: a file in a scratch folder named as the user knows it
// (its own name), never by the server's path.
std::string without_folder(std::string message, const std::filesystem::path& dir);

// Where a server given no --scratch keeps its scratch folders: "<temp>/bathyslam-server-<pid>".
std::filesystem::path default_scratch_root(const std::filesystem::path& temp, int pid);

// Removes the default scratch folders under `temp` whose server is no longer running: a server
// killed with SIGKILL cannot remove its own, and it holds a job's copy of its survey (gigabytes
// for a large one). Folders of running processes, and those it may not remove, stay. Returns
// how many it removed.
int remove_dead_servers_scratch(const std::filesystem::path& temp);

}  // namespace bathyslam::server
