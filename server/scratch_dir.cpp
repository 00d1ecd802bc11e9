#include "server/scratch_dir.h"

#include <signal.h>
#include <stdlib.h>

#include <cerrno>
#include <stdexcept>
#include <string>
#include <string_view>

namespace bathyslam::server {

ScratchDir::ScratchDir(const std::filesystem::path& root, const std::string& prefix) {
  std::filesystem::create_directories(root);
  std::string pattern = (root / (prefix + ".XXXXXX")).string();
  if (mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("cannot make a scratch folder in " + root.string());
  path_ = pattern;
}

ScratchDir::~ScratchDir() {
  std::error_code ignored;
  std::filesystem::remove_all(path_, ignored);
}

std::string without_folder(std::string message, const std::filesystem::path& dir) {
  const std::string folder = dir.string() + "/";
  for (std::string::size_type at; (at = message.find(folder)) != std::string::npos;) message.erase(at, folder.size());
  return message;
}

namespace {

constexpr std::string_view kDefaultPrefix = "bathyslam-server-";

// The pid a default scratch folder's name carries, or 0.
int pid_of(const std::string& name) {
  if (name.rfind(kDefaultPrefix, 0) != 0 || name.size() == kDefaultPrefix.size()) return 0;
  int pid = 0;
  for (char c : name.substr(kDefaultPrefix.size())) {
    if (c < '0' || c > '9' || pid > 100'000'000) return 0;  // no overflow below: pids are far smaller
    pid = 10 * pid + (c - '0');
  }
  return pid;
}

// EPERM: the process exists, another user's.
bool running(int pid) { return kill(pid, 0) == 0 || errno != ESRCH; }

}  // namespace

std::filesystem::path default_scratch_root(const std::filesystem::path& temp, int pid) {
  return temp / (std::string(kDefaultPrefix) + std::to_string(pid));
}

int remove_dead_servers_scratch(const std::filesystem::path& temp) {
  std::error_code error;
  int removed = 0;
  try {  // a folder that cannot be listed to the end must not stop the server from starting
    for (const auto& entry : std::filesystem::directory_iterator(temp, error)) {
      const int pid = pid_of(entry.path().filename().string());
      if (pid <= 0 || running(pid) || !entry.is_directory(error)) continue;
      if (std::filesystem::remove_all(entry.path(), error) != static_cast<std::uintmax_t>(-1) && !error) ++removed;
    }
  } catch (const std::filesystem::filesystem_error&) {
  }
  return removed;
}

}  // namespace bathyslam::server
